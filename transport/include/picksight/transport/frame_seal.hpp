// Frames sealed once for every subscriber. With CURVE on the PUB socket,
// ZeroMQ encrypts each subscriber's copy of a frame apart, on the I/O
// thread of its connection: at 8 full-HD subscribers and 60 fps the server
// could not keep up. A video server with CURVE instead seals each frame
// once, with a key of its own made at start (XChaCha20-Poly1305 from
// libsodium), and sends it on a plain PUB socket. Subscribers ask the key
// over the control socket (proto::FrameKeyRequest), which CURVE encrypts
// and whose allow-list admits them: only they can open a frame, and a frame
// changed on the way does not open.
//
// A sealed frame is the usual three parts, the topic (the camera name) in
// clear so that ZeroMQ can filter subscriptions:
//   part 2: "PSF1", the key id (8 bytes, little-endian), a random nonce
//           (24 bytes), then the FrameHeader sealed (its bytes + 16);
//   part 3: the pixel bytes sealed (+ 16), with the nonce plus one.
// Both are bound to the topic and to part 2's first 36 bytes: no part can
// be moved to another frame or camera, or its key id changed, unseen.
#pragma once

#include <array>
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

// A fresh random key and id (libsodium's generator).
FrameKey newFrameKey();

// Bytes a sealed part carries beyond what it seals.
constexpr size_t kSealedHeaderOverhead = 4 + 8 + 24 + 16;
constexpr size_t kSealTag = 16;

// Sends `frame` sealed with `key` (topic = its camera). The pixels are
// encrypted straight into the message ZeroMQ sends: one copy, as the
// cipher must write somewhere. Throws zmq::error_t like socket sends.
void sendSealedFrame(zmq::socket_t& socket, const Frame& frame, const FrameKey& key);

// The key id a sealed part 2 names, or nullopt when it is not one (a plain
// frame's header, or too short).
std::optional<uint64_t> sealedKeyId(const zmq::message_t& envelope);

// The header bytes and the pixels of a sealed frame opened with `key`, or
// nullopt when it does not open (another key, a changed byte, a part from
// another frame or camera).
struct OpenedFrame {
  std::string header;
  zmq::message_t pixels;
};
std::optional<OpenedFrame> openSealedFrame(const zmq::message_t& topic,
                                           const zmq::message_t& envelope,
                                           const zmq::message_t& pixels, const FrameKey& key);

}  // namespace picksight::transport
