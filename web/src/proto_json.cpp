// The protobuf JSON mapping with proto field names.
#include "picksight/web/proto_json.hpp"

#include <google/protobuf/util/json_util.h>

namespace picksight::web {

std::string protoJsonText(const google::protobuf::Message& message, bool with_defaults) {
  std::string text;
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  options.always_print_primitive_fields = with_defaults;
  if (!google::protobuf::util::MessageToJsonString(message, &text, options).ok()) return "{}";
  return text;
}

nlohmann::json protoJson(const google::protobuf::Message& message, bool with_defaults) {
  return nlohmann::json::parse(protoJsonText(message, with_defaults), nullptr, false);
}

}  // namespace picksight::web
