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

Result<CameraOutput> CameraLink::output() {
  return makeError(CameraErrc::kCameraRefused, "camera " + camera() + " has no output settings");
}
Result<void> CameraLink::setOutput(const CameraOutput&) {
  return makeError(CameraErrc::kCameraRefused, "camera " + camera() + " has no output settings");
}

namespace {
// A part of the camera's settings it does not have, as opposed to a link
// that has none at all.
bool lacks(const Error& e) {
  return e.code == CameraErrc::kCameraRefused || e.code == CameraErrc::kUnknownFeature;
}
}  // namespace

Result<CameraSetup> CameraLink::setup(const std::vector<std::string>& feature_names) {
  CameraSetup out;
  auto roi_now = roi();
  if (!roi_now && !lacks(roi_now.error())) return roi_now.error();
  if (roi_now) out.roi = *roi_now;
  auto output_now = output();
  if (!output_now && !lacks(output_now.error())) return output_now.error();
  if (output_now) out.output = *output_now;
  auto mode_now = mode();
  if (!mode_now && !lacks(mode_now.error())) return mode_now.error();
  if (mode_now) out.mode = *mode_now;
  for (const auto& name : feature_names) {
    auto value = feature(name);
    // A feature the camera does not know may come back as any refusal.
    if (!value && value.error().code == CameraErrc::kNoVideoServer) return value.error();
    if (value) out.features.emplace_back(name, *value);
  }
  return out;
}

Result<void> CameraLink::applySetup(const CameraSetup& s) {
  if (s.roi) {
    if (auto ok = setRoi(*s.roi); !ok) return ok;
  }
  if (s.output) {
    if (auto ok = setOutput(*s.output); !ok) return ok;
  }
  if (s.mode) {
    if (auto ok = setMode(*s.mode); !ok) return ok;
  }
  for (const auto& [name, value] : s.features) {
    if (auto ok = setFeature(name, value); !ok) return ok.error();
  }
  return {};
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
