// The frame wire format: a 3-part ZeroMQ message (topic = camera name,
// serialized FrameHeader, pixel bytes), and a subscriber that receives it.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include <opencv2/core.hpp>
#include <zmq.hpp>

#include "picksight.pb.h"

namespace picksight {

// One received frame. Owns its pixel bytes; image() is a view on them.
struct ReceivedFrame {
  proto::FrameHeader header;
  zmq::message_t pixels;
  // Local CLOCK_MONOTONIC time the frame was received: tells a frame that
  // arrived after a request from an older one, whatever the sender's clock.
  uint64_t received_ns = 0;

  // A cv::Mat header over the pixel bytes (CV_8UC1 or CV_8UC3), no copy;
  // valid while this ReceivedFrame lives.
  cv::Mat image() const;
};

// Bytes per pixel of a wire pixel format (0 for unknown).
int bytesPerPixel(proto::PixelFormat format);

// Checks that a header and a payload describe a consistent image.
bool frameIsConsistent(const proto::FrameHeader& header, size_t payload_size);

// Subscribes to the frames of one camera (or all cameras with an empty name).
// Owned and used by one thread, like the ZeroMQ socket inside it.
class FrameSubscriber {
 public:
  // `queue_frames` bounds the frames ZeroMQ buffers for us: a subscriber that
  // falls behind loses the oldest pending frames beyond it, never slows the server.
  FrameSubscriber(zmq::context_t& context, const std::string& endpoint, const std::string& camera,
                  int queue_frames = 4);

  // The next frame, or nullopt on timeout. Malformed messages are skipped and
  // counted, never returned.
  std::optional<ReceivedFrame> receive(std::chrono::milliseconds timeout);

  uint64_t malformedMessages() const { return malformed_; }
  // Frames this subscriber missed: gaps in each camera's sequence numbers
  // (a slow reader's own losses, or frames the camera lost). A sequence that
  // goes back (a restarted server) starts counting afresh.
  uint64_t framesLost() const { return lost_; }
  uint64_t framesReceived() const { return received_; }
  zmq::socket_t& socket() { return socket_; }

 private:
  zmq::socket_t socket_;
  std::string camera_;
  uint64_t malformed_ = 0;
  uint64_t lost_ = 0;
  uint64_t received_ = 0;
  std::map<std::string, uint64_t> last_sequence_;  // per camera
};

}  // namespace picksight
