// The vision app's link to its camera: fresh frames and camera settings.
// An interface so that the command layer can run with the video server
// (VideoServerCamera), with a still image (StillCamera: tests, offline work)
// or with no camera at all (NoCamera: the fuzzer, where every command that
// needs a frame must still answer, after checking its arguments).
//
// Threading: VisionService serializes calls to freshFrame() and control();
// framesReceived() may be called from any thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

#include <opencv2/core.hpp>
#include <zmq.hpp>

#include "picksight.pb.h"
#include "picksight/camera_link/frame_feed.hpp"
#include "picksight/common/result.hpp"
#include "picksight/transport/control_client.hpp"
#include "picksight/transport/frame_message.hpp"

namespace picksight::app {

// Why a camera link failed.
enum class CameraErrc {
  kNoFrame = 1,    // no fresh frame in time
  kNoVideoServer,  // the video server did not answer or refused
  kCameraRefused,  // the camera refused a setting
};
const char* errorName(CameraErrc e);
PICKSIGHT_ERROR_DOMAIN(CameraErrc, "camera link")

class CameraLink {
 public:
  virtual ~CameraLink() = default;
  virtual void start() {}
  virtual void stop() {}
  // A frame taken after this call.
  virtual Result<std::shared_ptr<const ReceivedFrame>> freshFrame() = 0;
  // One control request to the video server (the camera is filled in).
  virtual Result<proto::ControlReply> control(proto::ControlRequest request) = 0;
  virtual uint64_t framesReceived() const = 0;
  virtual const std::string& camera() const = 0;
};

// Frames from a video server: a software trigger (or the next free-run
// frame) on the control socket, the frame from the subscriber thread.
class VideoServerCamera : public CameraLink {
 public:
  VideoServerCamera(zmq::context_t& context, const std::string& frames_endpoint,
                    const std::string& control_endpoint, std::string camera,
                    std::chrono::milliseconds frame_timeout);
  void start() override { feed_.start(); }
  void stop() override { feed_.stop(); }
  Result<std::shared_ptr<const ReceivedFrame>> freshFrame() override;
  Result<proto::ControlReply> control(proto::ControlRequest request) override;
  uint64_t framesReceived() const override { return feed_.framesReceived(); }
  const std::string& camera() const override { return camera_; }

 private:
  const std::string camera_;
  const std::chrono::milliseconds frame_timeout_;
  FrameFeed feed_;
  ControlClient control_;
};

// One image served as every fresh frame (sequence numbers count up). The
// image can be replaced at any time; control requests are refused.
class StillCamera : public CameraLink {
 public:
  explicit StillCamera(cv::Mat image = cv::Mat(), std::string camera = "still");
  void setImage(const cv::Mat& image);
  Result<std::shared_ptr<const ReceivedFrame>> freshFrame() override;
  Result<proto::ControlReply> control(proto::ControlRequest request) override;
  uint64_t framesReceived() const override;
  const std::string& camera() const override { return camera_; }

 private:
  const std::string camera_;
  mutable std::mutex mutex_;  // guards image_ and sequence_
  cv::Mat image_;
  uint64_t sequence_ = 0;
};

// No camera: every frame request fails at once with CameraErrc::kNoFrame and every
// control request with CameraErrc::kNoVideoServer.
class NoCamera : public CameraLink {
 public:
  Result<std::shared_ptr<const ReceivedFrame>> freshFrame() override;
  Result<proto::ControlReply> control(proto::ControlRequest request) override;
  uint64_t framesReceived() const override { return 0; }
  const std::string& camera() const override { return camera_; }

 private:
  const std::string camera_ = "none";
};

// A ReceivedFrame holding a copy of a grey or BGR image (for StillCamera
// and tests).
std::shared_ptr<const ReceivedFrame> frameFromImage(const cv::Mat& image, const std::string& camera,
                                                    uint64_t sequence);

}  // namespace picksight::app

PICKSIGHT_ERROR_ENUM(picksight::app::CameraErrc)
