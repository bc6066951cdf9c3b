// Vision service: fresh frame, then blob location.
#include "picksight/vision_app/vision_service.hpp"

#include <opencv2/imgproc.hpp>

#include <cmath>

#include "picksight/common/clock.hpp"

namespace picksight::app {

std::vector<LocatedPart> locateParts(const ReceivedFrame& frame, const VisionOptions& options) {
  const auto& h = frame.header;
  cv::Mat grey = frame.image();
  if (grey.channels() == 3) {
    cv::Mat converted;
    cv::cvtColor(grey, converted, cv::COLOR_BGR2GRAY);
    grey = converted;
  }
  const cv::Mat mask = vision::binarize(grey, options.binarize);
  const auto regions = vision::findRegions(mask, options.regions, grey);
  const double sx = h.scale_x() > 0 ? h.scale_x() : 1.0;
  const double sy = h.scale_y() > 0 ? h.scale_y() : 1.0;
  std::vector<LocatedPart> parts;
  parts.reserve(regions.size());
  for (const auto& r : regions) {
    LocatedPart p;
    // Pixel centres are at integer coordinates in both frames.
    p.x = h.roi_x() + (r.centroid.x + 0.5) / sx - 0.5;
    p.y = h.roi_y() + (r.centroid.y + 0.5) / sy - 0.5;
    // A direction scales like a displacement: undo an anisotropic resize.
    const double a = r.angle_deg * M_PI / 180.0;
    double deg = std::atan2(std::sin(a) / sy, std::cos(a) / sx) * 180.0 / M_PI;
    if (deg < 0) deg += 360.0;
    p.angle_deg = deg;
    p.area = r.area / (sx * sy);
    p.holes = r.holes;
    parts.push_back(p);
  }
  return parts;
}

VisionService::VisionService(zmq::context_t& context, const std::string& frames_endpoint,
                             const std::string& control_endpoint, std::string camera,
                             VisionOptions options)
    : camera_(std::move(camera)),
      options_(std::move(options)),
      feed_(context, frames_endpoint, camera_),
      control_(context, control_endpoint) {}

void VisionService::start() { feed_.start(); }
void VisionService::stop() { feed_.stop(); }

Result<std::shared_ptr<const ReceivedFrame>> VisionService::freshFrame() {
  const uint64_t requested_ns = monotonicNs();
  proto::ControlRequest request;
  request.mutable_trigger()->set_camera(camera_);
  auto reply = control_.call(request);
  if (!reply) {
    return makeError(kNoVideoServer, "video server: " + reply.error().message);
  }
  const uint64_t sequence = reply->trigger().sequence();
  auto frame = feed_.waitFor(sequence, requested_ns, options_.frame_timeout);
  if (!frame) {
    return makeError(kNoFrame, "no frame from camera " + camera_ + " within " +
                                   std::to_string(options_.frame_timeout.count()) + " ms");
  }
  return frame;
}

Result<LocateOutcome> VisionService::locate() {
  std::lock_guard<std::mutex> lock(mutex_);
  auto frame = freshFrame();
  if (!frame) return frame.error();
  const auto& h = (*frame)->header;
  LocateOutcome outcome;
  outcome.frame = FrameInfo{h.camera(), h.sequence(), h.host_timestamp_ns(), h.width(), h.height(),
                            h.triggered()};
  outcome.parts = locateParts(**frame, options_);
  last_frame_ = outcome.frame;
  return outcome;
}

std::optional<FrameInfo> VisionService::lastFrame() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_frame_;
}

}  // namespace picksight::app
