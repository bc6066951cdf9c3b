// libFuzzer target: arbitrary bytes through the video server's control
// request path, as the control socket runs it but without a socket: the
// size bound, decoding, the field checks, the routing decisions and the
// error reply. Nothing may crash, hang or grow without bound, and whatever
// is accepted must be within the bounds the checks promise.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "picksight/video_server/camera.hpp"
#include "picksight/video_server/control_errors.hpp"
#include "picksight/video_server/control_request.hpp"
#include "picksight/video_server/frame_pipeline.hpp"

namespace {
void check(bool ok) {
  if (!ok) __builtin_trap();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace video = picksight::video;
  const auto decoded = video::decodeRequest(data, size);
  if (!decoded) {
    // Every refusal is an error reply with a code and a reason.
    const auto reply = video::errorReply(decoded.error());
    check(reply.error().code() != picksight::proto::Error::OK);
    check(!reply.error().text().empty());
    return 0;
  }
  const auto& request = *decoded;
  check(size <= picksight::transport::kMaxControlRequestBytes);
  check(request.request_case() != picksight::proto::ControlRequest::REQUEST_NOT_SET);
  const auto camera = video::requestCamera(request);
  if (camera) check(camera->size() <= video::kMaxControlName);
  (void)video::answeredAtOnce(request);
  if (request.has_set_mode()) {
    const double fps = request.set_mode().fps();
    check(std::isfinite(fps) && fps >= 0 && fps <= video::kMaxFps);
  }
  if (request.has_set_size()) {
    const double scale = request.set_size().scale();
    check(std::isfinite(scale) && scale >= 0 && scale <= video::kMaxOutputScale);
  }
  if (request.has_set_feature()) {
    check(request.set_feature().value().size() <= video::kMaxControlValue);
  }
  return 0;
}
