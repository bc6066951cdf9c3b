// Errors to control-reply codes, one table for the whole server.
#include "picksight/video_server/control_errors.hpp"

#include <array>
#include <utility>

#include "picksight/sources/source.hpp"
#include "picksight/video_server/video_errors.hpp"

namespace picksight::video {

const char* errorName(VideoErrc e) {
  switch (e) {
    case VideoErrc::kOutOfRange:
      return "out of range";
    case VideoErrc::kBadConfig:
      return "bad config";
    case VideoErrc::kUnknownCamera:
      return "unknown camera";
    case VideoErrc::kCameraClosed:
      return "camera closed";
    case VideoErrc::kNoFrame:
      return "no frame";
    case VideoErrc::kNotSupported:
      return "not supported";
    case VideoErrc::kBusy:
      return "busy";
    case VideoErrc::kBadRequest:
      return "bad request";
    case VideoErrc::kInternal:
      return "internal";
  }
  return "unknown";
}

namespace {
using Wire = proto::Error;

const std::array<std::pair<std::error_code, Wire::Code>, 16> kTable = {{
    {SourceErrc::kTimeout, Wire::TIMEOUT},
    {SourceErrc::kUnavailable, Wire::CAMERA_UNAVAILABLE},
    {SourceErrc::kBadConfig, Wire::BAD_REQUEST},
    {SourceErrc::kUnknownFeature, Wire::UNKNOWN_FEATURE},
    {SourceErrc::kBadValue, Wire::OUT_OF_RANGE},
    {SourceErrc::kNotSupported, Wire::NOT_SUPPORTED},
    {VideoErrc::kOutOfRange, Wire::OUT_OF_RANGE},
    {VideoErrc::kBadConfig, Wire::BAD_REQUEST},
    {VideoErrc::kUnknownCamera, Wire::UNKNOWN_CAMERA},
    {VideoErrc::kCameraClosed, Wire::CAMERA_UNAVAILABLE},
    {VideoErrc::kNoFrame, Wire::TIMEOUT},
    {VideoErrc::kNotSupported, Wire::NOT_SUPPORTED},
    {VideoErrc::kBusy, Wire::BUSY},
    {VideoErrc::kBadRequest, Wire::BAD_REQUEST},
    {VideoErrc::kInternal, Wire::INTERNAL},
    {std::error_code(), Wire::OK},
}};
}  // namespace

proto::Error::Code controlCode(const std::error_code& code) {
  for (const auto& [known, wire] : kTable) {
    if (known == code) return wire;
  }
  return Wire::INTERNAL;
}

proto::ControlReply errorReply(const Error& error) {
  proto::ControlReply reply;
  reply.mutable_error()->set_code(controlCode(error.code));
  reply.mutable_error()->set_text(error.message);
  return reply;
}

}  // namespace picksight::video
