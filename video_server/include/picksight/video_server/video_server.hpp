// The video server: cameras, the frame publisher and the control socket,
// wired together. Its handle() answers control requests, one small function
// per request kind.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <zmq.hpp>

#include "picksight.pb.h"
#include "picksight/transport/curve_server.hpp"
#include "picksight/transport/frame_seal.hpp"
#include "picksight/video_server/camera.hpp"
#include "picksight/video_server/control_server.hpp"
#include "picksight/video_server/frame_publisher.hpp"
#include "picksight/video_server/server_config.hpp"

namespace picksight::video {

class VideoServer {
 public:
  using SourceFactory = std::function<Result<std::unique_ptr<Source>>(const std::string& uri)>;

  // Builds every source (with `make_source`, the driver factory unless a
  // test brings its own) and binds both sockets (CURVE servers when the
  // config has a secret key); throws std::runtime_error with a message
  // naming the camera, endpoint or key file when that fails.
  explicit VideoServer(const ServerConfig& config, const SourceFactory& make_source = makeSource);
  ~VideoServer();

  void start();
  void stop();

  const std::string& framesEndpoint() const { return publisher_->boundEndpoint(); }
  const std::string& controlEndpoint() const { return control_->boundEndpoint(); }

  // Answers one control request. Called concurrently from the control
  // socket thread and its workers (see control_server.hpp): it only reads
  // cameras_ and publisher_, fixed after construction, and Camera and
  // FramePublisher are safe from any thread.
  proto::ControlReply handle(const proto::ControlRequest& request);

 private:
  Camera* find(const std::string& name);
  proto::ControlReply listCameras();
  proto::ControlReply statistics(const proto::StatisticsRequest& request);

  // Two I/O threads: the control socket's CURVE and the frames' sends.
  // (Before frames were sealed once each, CURVE encrypted each
  // subscriber's copy on the I/O thread of its connection.)
  zmq::context_t context_{2};
  // Before the sockets: its ZAP handler's socket closes after theirs.
  std::unique_ptr<transport::CurveServer> curve_;
  // With CURVE: the key every frame is sealed with, made at start; given
  // over the control socket (FrameKeyRequest).
  std::optional<transport::FrameKey> frame_key_;
  std::unique_ptr<FramePublisher> publisher_;
  std::vector<std::unique_ptr<Camera>> cameras_;
  std::unique_ptr<ControlServer> control_;
};

}  // namespace picksight::video
