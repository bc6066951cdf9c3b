// Frames sealed once for every subscriber. With CURVE on the PUB socket,
// ZeroMQ encrypts each subscriber's copy of a frame apart, on the I/O
// thread of its connection: at 8 full-HD subscribers and 60 fps the server
// could not keep up. A video server with CURVE instead seals each frame
// once, with a key of its own made at start (ChaCha20-Poly1305, RFC 8439,
// from OpenSSL: 0.5 ms a full-HD frame where libsodium took 1.6 and
// CURVE's own cipher 1.5), and sends it on a plain PUB socket. Subscribers ask the key
// over the control socket (proto::FrameKeyRequest), which CURVE encrypts
// and whose allow-list admits them: only they can open a frame, and a frame
// changed on the way does not open.
//
// A sealed frame is the usual three parts, the topic (the camera name) in
// clear so that ZeroMQ can filter subscriptions:
//   part 2: "PSF1", the key id (8 bytes, little-endian), the nonce (12
//           bytes), then the FrameHeader sealed (its bytes + 16);
//   part 3: the pixel bytes sealed (+ 16), with the nonce plus one (the
//           12 bytes read as a little-endian number).
// Both are bound to the topic and to part 2's first 24 bytes: no part can
// be moved to another frame or camera, or its key id changed, unseen. The
// nonces are a random prefix and a count (FrameSealer): never one twice
// under a key.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>

#include <zmq.hpp>

#include "picksight/common/frame.hpp"

namespace picksight::transport {

struct FrameKey {
  std::array<unsigned char, 32> key{};
  uint64_t id = 0;  // random: names the key, not secret
};

// A fresh random key and id (OpenSSL's generator).
FrameKey newFrameKey();

// Bytes a sealed part carries beyond what it seals.
constexpr size_t kSealedHeaderOverhead = 4 + 8 + 12 + 16;
constexpr size_t kSealTag = 16;

// Seals frames with one key, each under nonces of its own. Safe from any
// thread (the count is atomic).
class FrameSealer {
 public:
  explicit FrameSealer(const FrameKey& key);
  const FrameKey& key() const { return key_; }

  // Sends `frame` sealed (topic = its camera). The pixels are encrypted
  // straight into the message ZeroMQ sends: one copy, as the cipher must
  // write somewhere. Throws zmq::error_t like socket sends.
  void send(zmq::socket_t& socket, const Frame& frame);

 private:
  const FrameKey key_;
  std::array<unsigned char, 4> prefix_{};  // random: the nonces' first bytes
  std::atomic<uint64_t> count_{0};         // two nonces a frame
};

// The key id a sealed part 2 names, or nullopt when it is not one (a plain
// frame's header, or too short).
std::optional<uint64_t> sealedKeyId(const zmq::message_t& envelope);

// The header bytes of a sealed frame opened with `key`, its pixels opened
// in place in `pixels` (the first size - kSealTag bytes; no copy: a
// subscriber's share of the cost is this one pass), or nullopt when it
// does not open (another key, a changed byte, a part from another frame
// or camera); `pixels` is then garbage.
std::optional<std::string> openSealedFrame(const zmq::message_t& topic,
                                           const zmq::message_t& envelope, zmq::message_t& pixels,
                                           const FrameKey& key);

}  // namespace picksight::transport
