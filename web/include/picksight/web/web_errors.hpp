// The web server's error domain: what an HTTP request or the start-up can
// fail on; web_server.cpp maps each to its HTTP status in one place.
#pragma once

#include "picksight/common/error.hpp"

namespace picksight::web {

enum class WebErrc {
  kBadRequest = 1,  // malformed body or parameter
  kNotFound,        // unknown camera, app or file
  kUnreachable,     // a video server or vision app did not answer
  kEncode,          // an image could not be encoded
  kBadConfig,       // options or the YAML file
  kConflict,        // the request contradicts the state: the last admin, a user that exists
};
const char* errorName(WebErrc e);
PICKSIGHT_ERROR_DOMAIN(WebErrc, "web")

}  // namespace picksight::web

PICKSIGHT_ERROR_ENUM(picksight::web::WebErrc)
