// Camera links without a video server: a still image, or none.
#include "picksight/link/camera_link.hpp"

namespace picksight::link {

const char* errorName(CameraErrc e) {
  switch (e) {
    case CameraErrc::kNoFrame:
      return "no frame";
    case CameraErrc::kNoVideoServer:
      return "no video server";
    case CameraErrc::kCameraRefused:
      return "camera refused";
    case CameraErrc::kUnknownFeature:
      return "unknown feature";
    case CameraErrc::kNoTriggerPulse:
      return "no trigger pulse";
  }
  return "unknown";
}

Result<CameraModeSettings> CameraLink::mode() {
  return makeError(CameraErrc::kCameraRefused, "camera " + camera() + " has no acquisition modes");
}
Result<void> CameraLink::setMode(const CameraModeSettings&) {
  return makeError(CameraErrc::kCameraRefused, "camera " + camera() + " has no acquisition modes");
}

// The still image is copied once here, so the caller may reuse its own.
StillCamera::StillCamera(const cv::Mat& image, std::string camera)
    : camera_(std::move(camera)), image_(image.clone()) {}

void StillCamera::setImage(const cv::Mat& image) {
  std::lock_guard<std::mutex> lock(mutex_);
  image_ = image.clone();
}

Result<std::shared_ptr<const Frame>> StillCamera::freshFrame() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (image_.empty() || (image_.type() != CV_8UC1 && image_.type() != CV_8UC3))
    return makeError(CameraErrc::kNoFrame, "no image for camera " + camera_);
  // No copy: setImage replaces image_ instead of writing into it.
  return std::make_shared<const Frame>(frameFromImage(image_, camera_, ++sequence_));
}

Error StillCamera::noSettings() const {
  return makeError(CameraErrc::kNoVideoServer,
                   "camera " + camera_ + " is a still image: no settings");
}
Result<std::string> StillCamera::feature(const std::string&) { return noSettings(); }
Result<std::string> StillCamera::setFeature(const std::string&, const std::string&) {
  return noSettings();
}
Result<cv::Rect> StillCamera::roi() { return noSettings(); }
Result<void> StillCamera::setRoi(const cv::Rect&) { return noSettings(); }

uint64_t StillCamera::framesReceived() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return sequence_;
}

Result<std::shared_ptr<const Frame>> NoCamera::freshFrame() {
  return makeError(CameraErrc::kNoFrame, "no camera");
}
Result<std::string> NoCamera::feature(const std::string&) {
  return makeError(CameraErrc::kNoVideoServer, "no video server");
}
Result<std::string> NoCamera::setFeature(const std::string&, const std::string&) {
  return makeError(CameraErrc::kNoVideoServer, "no video server");
}
Result<cv::Rect> NoCamera::roi() {
  return makeError(CameraErrc::kNoVideoServer, "no video server");
}
Result<void> NoCamera::setRoi(const cv::Rect&) {
  return makeError(CameraErrc::kNoVideoServer, "no video server");
}

}  // namespace picksight::link
