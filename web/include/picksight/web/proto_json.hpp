// Protobuf messages as JSON the way the HTTP API writes them: the protobuf
// JSON mapping with the .proto field names (snake_case), on one line.
#pragma once

#include <string>

#include <google/protobuf/message.h>
#include <nlohmann/json.hpp>

namespace picksight::web {

// With `with_defaults` fields at their default value are written too (the
// mapping leaves them out otherwise: readers treat a missing field as 0).
std::string protoJsonText(const google::protobuf::Message& message, bool with_defaults = false);
nlohmann::json protoJson(const google::protobuf::Message& message, bool with_defaults = false);

}  // namespace picksight::web
