// Names of the web server's errors, for logs.
#include "picksight/web/web_errors.hpp"

namespace picksight::web {

const char* errorName(WebErrc e) {
  switch (e) {
    case WebErrc::kBadRequest:
      return "bad request";
    case WebErrc::kNotFound:
      return "not found";
    case WebErrc::kUnreachable:
      return "unreachable";
    case WebErrc::kEncode:
      return "encode";
    case WebErrc::kBadConfig:
      return "bad config";
    case WebErrc::kConflict:
      return "conflict";
  }
  return "unknown";
}

}  // namespace picksight::web
