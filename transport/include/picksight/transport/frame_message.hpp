// The frame codec: a Frame on the wire is a 3-part ZeroMQ message (topic =
// camera name, serialized FrameHeader, pixel bytes); the encoder and the
// decoder live side by side here, with the subscriber that receives frames.
// Protobuf and ZeroMQ types stop at this library: everything past the
// decoder is a Frame.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include <zmq.hpp>

#include "picksight.pb.h"
#include "picksight/common/frame.hpp"
#include "picksight/transport/curve_keys.hpp"
#include "picksight/transport/frame_seal.hpp"

namespace picksight::transport {

// ------------------------------------------------------------------ encoder

// The wire header of a frame (its width, height, stride and pixel format are
// the image's).
proto::FrameHeader frameHeaderOf(const Frame& frame);

// Sends `frame` as one message (topic = its camera) without copying the
// pixels of a continuous image: ZeroMQ holds a reference to them until the
// last subscriber was sent them. Throws zmq::error_t like socket sends.
void sendFrame(zmq::socket_t& socket, const Frame& frame);

// ------------------------------------------------------------------ decoder

// Bytes per pixel of a wire pixel format (0 for unknown).
int bytesPerPixel(proto::PixelFormat format);

// Checks that a header and a payload describe a consistent image.
bool frameIsConsistent(const proto::FrameHeader& header, size_t payload_size);

// The frame a header and its pixel bytes describe, or nullopt when they are
// not consistent. No copy: the frame's image is a view on `pixels`, which
// the frame's owner keeps alive. received_ns is left for the caller to stamp.
std::optional<Frame> decodeFrame(const proto::FrameHeader& header, zmq::message_t pixels);

// Subscribes to the frames of one camera (or all cameras with an empty name).
// Owned and used by one thread, like the ZeroMQ socket inside it.
class FrameSubscriber {
 public:
  // `queue_frames` bounds the frames ZeroMQ buffers for us: a subscriber that
  // falls behind loses the oldest pending frames beyond it, never slows the server.
  // With `curve` keys it takes only sealed frames (frame_seal.hpp), whose
  // key it asks at `control_endpoint` with those keys (required then: an
  // empty one throws std::invalid_argument): a plain frame, one that does
  // not open, or one sent again (its sequence not past the last) is
  // counted malformed and skipped. The key is asked again, at most once a
  // second, when frames name another (a restarted server). It is first
  // asked here (blocking up to the control timeout when nobody answers).
  FrameSubscriber(zmq::context_t& context, const std::string& endpoint, const std::string& camera,
                  int queue_frames = 4, const std::optional<CurveClientKeys>& curve = {},
                  const std::string& control_endpoint = {});
  ~FrameSubscriber();

  // The next frame, decoded and stamped with its local receive time, or
  // nullopt on timeout. Malformed messages are skipped and counted, never
  // returned.
  std::optional<Frame> receive(std::chrono::milliseconds timeout);

  uint64_t malformedMessages() const { return malformed_; }
  // Frames this subscriber missed: gaps in each camera's sequence numbers
  // (a slow reader's own losses, or frames the camera lost). A sequence that
  // goes back (a restarted server) starts counting afresh.
  uint64_t framesLost() const { return lost_; }
  uint64_t framesReceived() const { return received_; }
  // Sealed frames that named a key the control socket did not give (a
  // refused client never gets one).
  uint64_t framesUnopened() const { return unopened_; }
  zmq::socket_t& socket() { return socket_; }

 private:
  // Asks the frames' key on the control socket (blocking up to its
  // timeout); key_ is left as it was when none comes.
  void askKey();
  // The frame in a sealed message's parts (its pixels opened in place),
  // or nullopt (counted).
  std::optional<Frame> openSealed(const zmq::message_t& topic, const zmq::message_t& envelope,
                                  zmq::message_t& pixels);

  zmq::context_t& context_;
  zmq::socket_t socket_;
  std::string camera_;
  std::optional<CurveClientKeys> curve_;
  std::string control_endpoint_;
  std::optional<FrameKey> key_;
  std::chrono::steady_clock::time_point key_asked_{};
  uint64_t unopened_ = 0;
  uint64_t malformed_ = 0;
  uint64_t lost_ = 0;
  uint64_t received_ = 0;
  std::map<std::string, uint64_t> last_sequence_;  // per camera
};

}  // namespace picksight::transport
