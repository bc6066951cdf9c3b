// The page's camera actions as control requests, and their replies as JSON:
// POST /api/cameras/<camera>/<action> with a JSON body (docs/WEB.md).
// Plain functions, no state.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "picksight.pb.h"
#include "picksight/common/result.hpp"

namespace picksight::web {

// A JSON library exception's message without its "[json.exception.X.N] "
// tag: what a client may read.
std::string plainJsonMessage(const nlohmann::json::exception& e);

// The JSON object of a request body (an empty body is {}); kBadRequest names
// the problem (bad JSON, not an object).
Result<nlohmann::json> parseJsonBody(const std::string& body);

// The control request of `action` ("roi", "size", "mode", "feature", "open",
// "close", "trigger", "target") for `camera`; kBadRequest names the field at
// fault, kNotFound an unknown action.
Result<proto::ControlRequest> cameraAction(const std::string& camera, const std::string& action,
                                           const nlohmann::json& body);

// {"ok":true, ...} with what the reply says (trigger sequence, feature,
// simulated robot).
nlohmann::json actionReplyJson(const proto::ControlReply& reply);

}  // namespace picksight::web
