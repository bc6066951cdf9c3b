// The camera link to a video server: a software trigger (or the next
// free-run frame, or the next hardware-triggered one: the camera's line is
// pulsed by the robot) on the control socket, the frame from a subscriber thread;
// camera settings as control requests. The only part of the vision app that
// speaks the video server's protocol.
//
// Threading: as CameraLink; the control socket is used by the caller's
// thread (VisionService serializes), the frames by the feed's thread.
// With CURVE keys both sockets are CURVE clients of the video server.
#pragma once

#include <chrono>
#include <optional>
#include <string>

#include <zmq.hpp>

#include "picksight/link/camera_link.hpp"
#include "picksight/link/frame_feed.hpp"
#include "picksight/transport/control_client.hpp"

namespace picksight::link {

class VideoServerCamera : public CameraLink {
 public:
  VideoServerCamera(zmq::context_t& context, const std::string& frames_endpoint,
                    const std::string& control_endpoint, std::string camera,
                    std::chrono::milliseconds frame_timeout,
                    const std::optional<transport::CurveClientKeys>& curve = std::nullopt);
  void start() override { feed_.start(); }
  void stop() override { feed_.stop(); }
  Result<std::shared_ptr<const Frame>> freshFrame() override;
  Result<std::string> feature(const std::string& name) override;
  Result<std::string> setFeature(const std::string& name, const std::string& value) override;
  Result<cv::Rect> roi() override;
  Result<void> setRoi(const cv::Rect& roi) override;
  Result<CameraModeSettings> mode() override;
  Result<void> setMode(const CameraModeSettings& mode) override;
  Result<CameraOutput> output() override;
  Result<void> setOutput(const CameraOutput& output) override;
  uint64_t framesReceived() const override { return feed_.framesReceived(); }
  const std::string& camera() const override { return camera_; }

 private:
  // One request to the video server, its errors as CameraErrc values.
  Result<proto::ControlReply> call(const proto::ControlRequest& request);
  // The frame of the next pulse on a hardware-triggered camera's line.
  Result<std::shared_ptr<const Frame>> hardwareFrame(const proto::TriggerReply& ticket,
                                                     uint64_t requested_ns);

  const std::string camera_;
  const std::chrono::milliseconds frame_timeout_;
  FrameFeed feed_;
  transport::ControlClient control_;
};

}  // namespace picksight::link
