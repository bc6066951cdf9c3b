// The video server: cameras, the frame publisher and the control socket,
// wired together. Its handle() answers control requests.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <zmq.hpp>

#include "picksight.pb.h"
#include "picksight/video_server/camera.hpp"
#include "picksight/video_server/control_server.hpp"
#include "picksight/video_server/frame_publisher.hpp"
#include "picksight/video_server/server_config.hpp"

namespace picksight::video {

class VideoServer {
 public:
  // Builds every source and binds both sockets; throws std::runtime_error
  // with a message naming the camera or endpoint when that fails.
  explicit VideoServer(const ServerConfig& config);
  ~VideoServer();

  void start();
  void stop();

  const std::string& framesEndpoint() const { return publisher_->boundEndpoint(); }
  const std::string& controlEndpoint() const { return control_->boundEndpoint(); }

  // Answers one control request (called on the control thread).
  proto::ControlReply handle(const proto::ControlRequest& request);

 private:
  Camera* find(const std::string& name);

  zmq::context_t context_;
  std::unique_ptr<FramePublisher> publisher_;
  std::vector<std::unique_ptr<Camera>> cameras_;
  std::unique_ptr<ControlServer> control_;
};

}  // namespace picksight::video
