// The page's view of a vision app's filmstrip, read through the app's robot
// (or set-up) port: picksight-web may run on another host than the app's
// data directory. The newest entries as their sidecars (FILMSTRIP, then
// FILMSTRIP SHOW of each), and one frame as PNG (FILMSTRIP IMAGE).
//
// Threading: as ResultFeed::command (its one line connection, serialized).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "picksight/common/result.hpp"
#include "picksight/web/result_feed.hpp"

namespace picksight::web {

// Most entries the page asks for at once.
constexpr size_t kMaxFilmstripEntries = 50;

// {"entries": [sidecar, ...]} newest first; an entry that cannot be shown
// is {"id": n, "error": "<the app's reply>"}. An app's ERROR reply is
// kConflict (kNotFound for ERROR 55) with that reply as the message.
Result<nlohmann::json> filmstripEntries(ResultFeed& app, size_t count, bool failures_only);

// Entry `id`'s frame as PNG bytes, shrunk to fit `side` pixels each way.
Result<std::string> filmstripPng(ResultFeed& app, uint64_t id, int side);

}  // namespace picksight::web
