// Camera links: the video server, a still image, or none.
#include "picksight/camera_link/camera_link.hpp"

#include <algorithm>

#include "picksight/common/clock.hpp"

namespace picksight::app {

const char* errorName(CameraErrc e) {
  switch (e) {
    case CameraErrc::kNoFrame:
      return "no frame";
    case CameraErrc::kNoVideoServer:
      return "no video server";
    case CameraErrc::kCameraRefused:
      return "camera refused";
  }
  return "unknown";
}

VideoServerCamera::VideoServerCamera(zmq::context_t& context, const std::string& frames_endpoint,
                                     const std::string& control_endpoint, std::string camera,
                                     std::chrono::milliseconds frame_timeout)
    : camera_(std::move(camera)),
      frame_timeout_(frame_timeout),
      feed_(context, frames_endpoint, camera_),
      control_(context, control_endpoint) {}

Result<std::shared_ptr<const ReceivedFrame>> VideoServerCamera::freshFrame() {
  // A triggered frame can be lost on the way (a subscription still joining,
  // a full queue): trigger again after a while rather than wait in vain for
  // the whole timeout. Any later frame will do.
  constexpr std::chrono::milliseconds kRetrigger{500};
  const uint64_t requested_ns = monotonicNs();
  const auto deadline = std::chrono::steady_clock::now() + frame_timeout_;
  for (;;) {
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) {
      return makeError(CameraErrc::kNoFrame, "no frame from camera " + camera_ + " within " +
                                                 std::to_string(frame_timeout_.count()) + " ms");
    }
    proto::ControlRequest request;
    request.mutable_trigger();
    auto reply = control(request);
    if (!reply)
      return makeError(CameraErrc::kNoVideoServer, "video server: " + reply.error().message);
    const auto wait = std::min<std::chrono::milliseconds>(
        kRetrigger, std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now));
    auto frame = feed_.waitFor(reply->trigger().sequence(), requested_ns, wait);
    if (frame) return frame;
  }
}

Result<proto::ControlReply> VideoServerCamera::control(proto::ControlRequest request) {
  // Every request that names a camera names ours.
  switch (request.request_case()) {
    case proto::ControlRequest::kTrigger:
      request.mutable_trigger()->set_camera(camera_);
      break;
    case proto::ControlRequest::kSetRoi:
      request.mutable_set_roi()->set_camera(camera_);
      break;
    case proto::ControlRequest::kSetFeature:
      request.mutable_set_feature()->set_camera(camera_);
      break;
    case proto::ControlRequest::kGetFeature:
      request.mutable_get_feature()->set_camera(camera_);
      break;
    case proto::ControlRequest::kDescribeCamera:
      request.mutable_describe_camera()->set_camera(camera_);
      break;
    default:
      break;
  }
  return control_.call(request);
}

std::shared_ptr<const ReceivedFrame> frameFromImage(const cv::Mat& image, const std::string& camera,
                                                    uint64_t sequence) {
  auto frame = std::make_shared<ReceivedFrame>();
  const cv::Mat dense = image.isContinuous() ? image : image.clone();
  auto& h = frame->header;
  h.set_camera(camera);
  h.set_sequence(sequence);
  h.set_host_timestamp_ns(realtimeNs());
  h.set_width(static_cast<uint32_t>(dense.cols));
  h.set_height(static_cast<uint32_t>(dense.rows));
  h.set_stride(static_cast<uint32_t>(dense.step[0]));
  h.set_pixel_format(dense.channels() == 3 ? proto::BGR8 : proto::MONO8);
  h.set_scale_x(1.0);
  h.set_scale_y(1.0);
  h.set_triggered(true);
  frame->pixels = zmq::message_t(dense.data, dense.total() * dense.elemSize());
  frame->received_ns = monotonicNs();
  return frame;
}

StillCamera::StillCamera(cv::Mat image, std::string camera)
    : camera_(std::move(camera)), image_(std::move(image)) {}

void StillCamera::setImage(const cv::Mat& image) {
  std::lock_guard<std::mutex> lock(mutex_);
  image_ = image.clone();
}

Result<std::shared_ptr<const ReceivedFrame>> StillCamera::freshFrame() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (image_.empty() || (image_.type() != CV_8UC1 && image_.type() != CV_8UC3))
    return makeError(CameraErrc::kNoFrame, "no image for camera " + camera_);
  return frameFromImage(image_, camera_, ++sequence_);
}

Result<proto::ControlReply> StillCamera::control(proto::ControlRequest) {
  return makeError(CameraErrc::kNoVideoServer,
                   "camera " + camera_ + " is a still image: no settings");
}

uint64_t StillCamera::framesReceived() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return sequence_;
}

Result<std::shared_ptr<const ReceivedFrame>> NoCamera::freshFrame() {
  return makeError(CameraErrc::kNoFrame, "no camera");
}

Result<proto::ControlReply> NoCamera::control(proto::ControlRequest) {
  return makeError(CameraErrc::kNoVideoServer, "no video server");
}

}  // namespace picksight::app
