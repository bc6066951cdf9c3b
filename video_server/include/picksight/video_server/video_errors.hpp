// The video server's own failures, beside the drivers' (SourceErrc): settings
// out of range, a bad configuration, requests for what does not exist. The
// control socket turns both into wire codes in one table (control_errors.hpp).
#pragma once

#include "picksight/common/error.hpp"

namespace picksight::video {

enum class VideoErrc {
  kOutOfRange = 1,  // a setting (ROI, size, scale, fps, format, mode) refused
  kBadConfig,       // the configuration file or the command line is wrong
  kUnknownCamera,   // no camera of that name
  kCameraClosed,    // the camera's stream is closed
  kNoFrame,         // no frame in time
  kNotSupported,    // a request this server does not serve
  kBusy,            // too much slow work pending; ask again later
  kBadRequest,      // a control message that does not decode, or asks nothing
  kInternal,        // a handler failed unexpectedly (a bug; logged)
};
const char* errorName(VideoErrc e);
PICKSIGHT_ERROR_DOMAIN(VideoErrc, "video")

}  // namespace picksight::video

PICKSIGHT_ERROR_ENUM(picksight::video::VideoErrc)
