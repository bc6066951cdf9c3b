// The camera link to a video server: triggers, frames and settings.
#include "picksight/link/video_server_camera.hpp"

#include <algorithm>

#include "picksight/common/clock.hpp"

namespace picksight::link {

using transport::ControlErrc;
using transport::CurveClientKeys;
using transport::kDefaultControlTimeout;

VideoServerCamera::VideoServerCamera(zmq::context_t& context, const std::string& frames_endpoint,
                                     const std::string& control_endpoint, std::string camera,
                                     std::chrono::milliseconds frame_timeout,
                                     const std::optional<CurveClientKeys>& curve)
    : camera_(std::move(camera)),
      frame_timeout_(frame_timeout),
      feed_(context, frames_endpoint, camera_, curve, control_endpoint),
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
    if (reply->trigger().mode() == proto::HARDWARE_TRIGGER) {
      return hardwareFrame(reply->trigger(), requested_ns);
    }
    // Nothing to lose in free-run: any later frame serves, and asking again
    // would only set a later bar (a stream's frames are held to the request).
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now);
    const auto wait = reply->trigger().triggered() ? std::min(kRetrigger, left) : left;
    auto frame = feed_.waitFor(reply->trigger().sequence(), requested_ns, wait);
    if (frame) return frame;
  }
}

Result<std::shared_ptr<const Frame>> VideoServerCamera::hardwareFrame(
    const proto::TriggerReply& ticket, uint64_t requested_ns) {
  // The frame comes when the line is pulsed (by the robot, after sending its
  // request): asking again would change nothing, so one wait, bounded by the
  // camera's trigger timeout, not by this link's own frame timeout.
  const std::chrono::milliseconds timeout(
      ticket.trigger_timeout_ms() > 0 ? ticket.trigger_timeout_ms() : frame_timeout_.count());
  const auto elapsed = std::chrono::nanoseconds(monotonicNs() - requested_ns);
  const auto left =
      std::max(std::chrono::milliseconds(0),
               timeout - std::chrono::duration_cast<std::chrono::milliseconds>(elapsed));
  if (auto frame = feed_.waitFor(ticket.sequence(), requested_ns, left)) return frame;
  return makeError(CameraErrc::kNoTriggerPulse, "camera " + camera_ +
                                                    " is in hardware trigger mode: no pulse on " +
                                                    ticket.trigger_line() + " within " +
                                                    std::to_string(timeout.count()) + " ms");
}

Result<CameraModeSettings> VideoServerCamera::mode() {
  proto::ControlRequest request;
  request.mutable_describe_camera()->set_camera(camera_);
  auto reply = call(request);
  if (!reply) return reply.error();
  const auto& d = reply->describe_camera();
  CameraModeSettings settings;
  switch (d.summary().mode()) {
    case proto::TRIGGER:
      settings.mode = CameraMode::kSoftwareTrigger;
      break;
    case proto::HARDWARE_TRIGGER:
      settings.mode = CameraMode::kHardwareTrigger;
      break;
    default:
      settings.mode = CameraMode::kFreeRun;
  }
  settings.fps = d.fps();
  settings.line = d.trigger_line();
  settings.timeout = std::chrono::milliseconds(d.trigger_timeout_ms());
  return settings;
}

Result<void> VideoServerCamera::setMode(const CameraModeSettings& settings) {
  proto::ControlRequest request;
  auto* set = request.mutable_set_mode();
  set->set_camera(camera_);
  switch (settings.mode) {
    case CameraMode::kFreeRun:
      set->set_mode(proto::FREERUN);
      set->set_fps(settings.fps);
      break;
    case CameraMode::kSoftwareTrigger:
      set->set_mode(proto::TRIGGER);
      break;
    case CameraMode::kHardwareTrigger:
      set->set_mode(proto::HARDWARE_TRIGGER);
      set->set_trigger_line(settings.line);
      set->set_trigger_timeout_ms(static_cast<uint32_t>(settings.timeout.count()));
      break;
  }
  auto reply = call(request);
  if (!reply) return reply.error();
  return {};
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

Result<CameraOutput> VideoServerCamera::output() {
  proto::ControlRequest request;
  request.mutable_describe_camera()->set_camera(camera_);
  auto reply = call(request);
  if (!reply) return reply.error();
  const auto& d = reply->describe_camera();
  CameraOutput out;
  out.width = d.output_width();
  out.height = d.output_height();
  out.pixel_format = d.pixel_format() == proto::BGR8    ? "bgr8"
                     : d.pixel_format() == proto::MONO8 ? "mono8"
                                                        : "";
  return out;
}

Result<void> VideoServerCamera::setOutput(const CameraOutput& output) {
  proto::ControlRequest size;
  auto* set = size.mutable_set_size();
  set->set_camera(camera_);
  set->set_width(output.width);
  set->set_height(output.height);
  if (auto reply = call(size); !reply) return reply.error();
  if (output.pixel_format.empty()) return {};
  proto::ControlRequest format;
  auto* f = format.mutable_set_format();
  f->set_camera(camera_);
  if (output.pixel_format == "mono8") {
    f->set_pixel_format(proto::MONO8);
  } else if (output.pixel_format == "bgr8") {
    f->set_pixel_format(proto::BGR8);
  } else {
    return makeError(CameraErrc::kCameraRefused,
                     "pixel format " + output.pixel_format + " unknown (mono8, bgr8)");
  }
  if (auto reply = call(format); !reply) return reply.error();
  return {};
}

}  // namespace picksight::link
