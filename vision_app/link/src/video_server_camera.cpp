// The camera link to a video server: triggers, frames and settings.
#include "picksight/camera_link/video_server_camera.hpp"

#include <algorithm>

#include "picksight/common/clock.hpp"

namespace picksight::app {

VideoServerCamera::VideoServerCamera(zmq::context_t& context, const std::string& frames_endpoint,
                                     const std::string& control_endpoint, std::string camera,
                                     std::chrono::milliseconds frame_timeout,
                                     const std::optional<CurveClientKeys>& curve)
    : camera_(std::move(camera)),
      frame_timeout_(frame_timeout),
      feed_(context, frames_endpoint, camera_, curve),
      control_(context, control_endpoint, kDefaultControlTimeout, curve) {}

Result<proto::ControlReply> VideoServerCamera::call(const proto::ControlRequest& request) {
  auto reply = control_.call(request);
  if (reply) return reply;
  const std::error_code code = reply.error().code;
  if (code == ControlErrc::kNoReply)
    return makeError(CameraErrc::kNoVideoServer, reply.error().message);
  if (code == ControlErrc::kUnknownFeature)
    return makeError(CameraErrc::kUnknownFeature, reply.error().message);
  return makeError(CameraErrc::kCameraRefused, reply.error().message);
}

Result<std::shared_ptr<const Frame>> VideoServerCamera::freshFrame() {
  // A triggered frame can be lost on the way (a subscription still joining,
  // a full queue): trigger again after a while rather than wait in vain for
  // the whole timeout. Any later frame will do.
  constexpr std::chrono::milliseconds kRetrigger{500};
  const uint64_t requested_ns = monotonicNs();
  const auto deadline = std::chrono::steady_clock::now() + frame_timeout_;
  proto::ControlRequest request;
  request.mutable_trigger()->set_camera(camera_);
  for (;;) {
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) {
      return makeError(CameraErrc::kNoFrame, "no frame from camera " + camera_ + " within " +
                                                 std::to_string(frame_timeout_.count()) + " ms");
    }
    // A camera in an outage refuses at once (camera refused, with its reason).
    auto reply = call(request);
    if (!reply) return reply.error();
    const auto wait = std::min<std::chrono::milliseconds>(
        kRetrigger, std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now));
    auto frame = feed_.waitFor(reply->trigger().sequence(), requested_ns, wait);
    if (frame) return frame;
  }
}

Result<std::string> VideoServerCamera::feature(const std::string& name) {
  proto::ControlRequest request;
  auto* get = request.mutable_get_feature();
  get->set_camera(camera_);
  get->set_name(name);
  auto reply = call(request);
  if (!reply) return reply.error();
  return reply->feature().feature().value();
}

Result<std::string> VideoServerCamera::setFeature(const std::string& name,
                                                  const std::string& value) {
  proto::ControlRequest request;
  auto* set = request.mutable_set_feature();
  set->set_camera(camera_);
  set->set_name(name);
  set->set_value(value);
  auto reply = call(request);
  if (!reply) return reply.error();
  return reply->feature().feature().value();
}

Result<cv::Rect> VideoServerCamera::roi() {
  proto::ControlRequest request;
  request.mutable_describe_camera()->set_camera(camera_);
  auto reply = call(request);
  if (!reply) return reply.error();
  const auto& d = reply->describe_camera();
  const auto& roi = d.roi();
  // A zero size is the full sensor.
  return cv::Rect(static_cast<int>(roi.x()), static_cast<int>(roi.y()),
                  static_cast<int>(roi.width() ? roi.width() : d.sensor_width()),
                  static_cast<int>(roi.height() ? roi.height() : d.sensor_height()));
}

Result<void> VideoServerCamera::setRoi(const cv::Rect& roi) {
  proto::ControlRequest request;
  auto* set = request.mutable_set_roi();
  set->set_camera(camera_);
  auto* r = set->mutable_roi();  // all zero: the full sensor
  if (!roi.empty()) {
    r->set_x(static_cast<uint32_t>(roi.x));
    r->set_y(static_cast<uint32_t>(roi.y));
    r->set_width(static_cast<uint32_t>(roi.width));
    r->set_height(static_cast<uint32_t>(roi.height));
  }
  auto reply = call(request);
  if (!reply) return reply.error();
  return {};
}

}  // namespace picksight::app
