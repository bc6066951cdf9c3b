// picksight-cam: prints a server's reply as text for people or as one JSON
// object for scripts.
#pragma once

#include <ostream>
#include <string>

#include <nlohmann/json.hpp>

#include "cam_command_line.hpp"
#include "picksight.pb.h"
#include "picksight/common/result.hpp"

namespace picksight::cam {

// Keys stay in the order the tool writes them, which is the order people read.
using Json = nlohmann::ordered_json;

// One line of compact JSON. Strings that are not valid UTF-8 (a camera's
// vendor string, say) get U+FFFD instead of making the output unreadable.
std::string toJson(const Json& value);

const char* formatName(proto::PixelFormat format);

// Prints the reply to `request` (and saves a snap to the command's FILE); an
// error when the reply lacks the part the request asks for (a server speaking
// another protocol version) or the snap cannot be saved.
Result<void> printReply(const proto::ControlRequest& request, const proto::ControlReply& reply,
                        const CamOptions& options, std::ostream& out);

}  // namespace picksight::cam
