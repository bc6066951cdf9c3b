// The vision app's link to its camera: fresh frames and camera settings.
// An interface so that the command layer can run with the video server
// (VideoServerCamera, video_server_camera.hpp), with a still image
// (StillCamera: tests, offline work) or with no camera at all (NoCamera: the
// fuzzer, where every command that needs a frame must still answer, after
// checking its arguments). Frames arrive decoded; no wire type crosses this
// interface.
//
// Threading: VisionService serializes calls to freshFrame() and the camera
// settings; framesReceived() may be called from any thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/common/frame.hpp"
#include "picksight/common/result.hpp"

namespace picksight::link {

// Why a camera link failed.
enum class CameraErrc {
  kNoFrame = 1,    // no fresh frame in time
  kNoVideoServer,  // the video server did not answer, or there is none
  kCameraRefused,  // the camera refused a setting
  // The camera has no setting of that name (kept apart so that a caller can
  // try another name; reported to robots as CameraErrc::kCameraRefused).
  kUnknownFeature,
  // The camera is in hardware-trigger mode and no pulse came on its line
  // within its trigger timeout (no software trigger is ever sent then).
  kNoTriggerPulse,
};

// How the camera acquires: free-run at fps, one frame per software trigger,
// or one per pulse on its trigger input `line` (the robot's digital output),
// a frame request waiting up to `timeout` for it.
enum class CameraMode { kFreeRun, kSoftwareTrigger, kHardwareTrigger };
struct CameraModeSettings {
  CameraMode mode = CameraMode::kFreeRun;
  double fps = 0;                        // kFreeRun; 0 = leave (as read: the setting)
  std::string line;                      // kHardwareTrigger; empty = the camera's default
  std::chrono::milliseconds timeout{0};  // kHardwareTrigger; 0 = the camera's default
};
const char* errorName(CameraErrc e);
PICKSIGHT_ERROR_DOMAIN(CameraErrc, "camera link")

// What the camera delivers after its ROI: the output size (0 x 0: the
// ROI's) and the pixel format ("mono8", "bgr8"; empty: the camera's own).
struct CameraOutput {
  uint32_t width = 0;
  uint32_t height = 0;
  std::string pixel_format;
};

// Every camera setting a job keeps (jobs/job_file.hpp): the ROI, the
// output, the acquisition mode and named features (exposure, gain). Each
// part the camera does not have is absent.
struct CameraSetup {
  std::optional<cv::Rect> roi;
  std::optional<CameraOutput> output;
  std::optional<CameraModeSettings> mode;
  std::vector<std::pair<std::string, std::string>> features;  // name, value as read
};

class CameraLink {
 public:
  virtual ~CameraLink() = default;
  virtual void start() {}
  virtual void stop() {}
  // A frame taken after this call.
  virtual Result<std::shared_ptr<const Frame>> freshFrame() = 0;

  // Camera settings by the name the camera knows (a GenICam feature, a V4L2
  // control), values as text. setFeature returns the value read back: a
  // camera may round or clamp.
  virtual Result<std::string> feature(const std::string& name) = 0;
  virtual Result<std::string> setFeature(const std::string& name, const std::string& value) = 0;
  // The sensor region the camera delivers, in sensor pixels; setRoi with an
  // empty rectangle selects the full sensor.
  virtual Result<cv::Rect> roi() = 0;
  virtual Result<void> setRoi(const cv::Rect& roi) = 0;
  // The acquisition mode; links without modes refuse (kCameraRefused).
  virtual Result<CameraModeSettings> mode();
  virtual Result<void> setMode(const CameraModeSettings& mode);
  // The output size and format; links without them refuse (kCameraRefused).
  virtual Result<CameraOutput> output();
  virtual Result<void> setOutput(const CameraOutput& output);

  // Reads every setting of a CameraSetup, the features those of
  // `feature_names` the camera has. kNoVideoServer when the link has no
  // settings at all (a still image, no camera); a part the camera lacks
  // (kCameraRefused, kUnknownFeature) is left out.
  Result<CameraSetup> setup(const std::vector<std::string>& feature_names);
  // Applies every part `setup` holds: ROI, output, mode, then features.
  // The first refusal stops and is returned (the caller puts back what it
  // read before).
  Result<void> applySetup(const CameraSetup& setup);

  virtual uint64_t framesReceived() const = 0;
  virtual const std::string& camera() const = 0;
};

// One image served as every fresh frame (sequence numbers count up). The
// image can be replaced at any time; camera settings are refused.
class StillCamera : public CameraLink {
 public:
  explicit StillCamera(const cv::Mat& image = cv::Mat(), std::string camera = "still");
  void setImage(const cv::Mat& image);
  Result<std::shared_ptr<const Frame>> freshFrame() override;
  Result<std::string> feature(const std::string& name) override;
  Result<std::string> setFeature(const std::string& name, const std::string& value) override;
  Result<cv::Rect> roi() override;
  Result<void> setRoi(const cv::Rect& roi) override;
  uint64_t framesReceived() const override;
  const std::string& camera() const override { return camera_; }

 private:
  Error noSettings() const;

  const std::string camera_;
  mutable std::mutex mutex_;  // guards image_ and sequence_
  cv::Mat image_;             // never written into: frames share it
  uint64_t sequence_ = 0;
};

// No camera: every frame request fails at once with CameraErrc::kNoFrame and every
// setting with CameraErrc::kNoVideoServer.
class NoCamera : public CameraLink {
 public:
  Result<std::shared_ptr<const Frame>> freshFrame() override;
  Result<std::string> feature(const std::string& name) override;
  Result<std::string> setFeature(const std::string& name, const std::string& value) override;
  Result<cv::Rect> roi() override;
  Result<void> setRoi(const cv::Rect& roi) override;
  uint64_t framesReceived() const override { return 0; }
  const std::string& camera() const override { return camera_; }

 private:
  const std::string camera_ = "none";
};

}  // namespace picksight::link

PICKSIGHT_ERROR_ENUM(picksight::link::CameraErrc)
