// Sealed frames: what one key seals opens with it alone, a change anywhere
// (or a part moved to another frame or camera) does not open, and a
// subscriber with CURVE keys takes sealed frames only, once each, with the
// key it asked on a real CURVE control socket.
#include <sys/stat.h>

#include <catch2/catch.hpp>
#include <cstring>
#include <thread>

#include "picksight.pb.h"
#include "picksight/transport/curve_keys.hpp"
#include "picksight/transport/curve_server.hpp"
#include "picksight/transport/frame_message.hpp"
#include "picksight/transport/frame_seal.hpp"
#include "temp_dir.hpp"

using namespace picksight;
using namespace picksight::transport;
using namespace std::chrono_literals;

namespace {

Frame testFrame(const std::string& camera, uint64_t sequence, int seed) {
  Frame f;
  f.image = cv::Mat(48, 64, CV_8UC1);
  cv::RNG rng(static_cast<uint64_t>(seed));
  rng.fill(f.image, cv::RNG::UNIFORM, 0, 256);
  f.info.camera = camera;
  f.info.sequence = sequence;
  return f;
}

// One sealed message's three parts, sent and received on a PAIR.
struct Parts {
  zmq::message_t topic, envelope, pixels;
};

Parts sealedParts(zmq::context_t& context, const Frame& frame, FrameSealer& sealer) {
  zmq::socket_t out(context, zmq::socket_type::pair);
  zmq::socket_t in(context, zmq::socket_type::pair);
  static int n = 0;
  const std::string endpoint = "inproc://seal-test-" + std::to_string(n++);
  in.bind(endpoint);
  out.connect(endpoint);
  sealer.send(out, frame);
  Parts p;
  REQUIRE(in.recv(p.topic));
  REQUIRE(in.recv(p.envelope));
  REQUIRE(in.recv(p.pixels));
  return p;
}

zmq::message_t copyOf(const zmq::message_t& m) { return zmq::message_t(m.data(), m.size()); }

// The frame in a sealed message, opened on a copy of its pixels (they are
// opened in place), or nullopt.
std::optional<Frame> opened(const zmq::message_t& topic, const zmq::message_t& envelope,
                            const zmq::message_t& pixels, const FrameKey& key) {
  zmq::message_t copy = copyOf(pixels);
  const auto header = openSealedFrame(topic, envelope, copy, key);
  if (!header) return std::nullopt;
  proto::FrameHeader h;
  REQUIRE(h.ParseFromString(*header));
  return decodeFrame(h, std::move(copy));
}

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a != b) == 0;
}

}  // namespace

TEST_CASE("A sealed frame opens with its key alone, to the frame sealed", "[transport][seal]") {
  zmq::context_t context;
  const FrameKey key = newFrameKey();
  FrameSealer sealer(key);
  const Frame frame = testFrame("cam0", 7, 1);
  const Parts p = sealedParts(context, frame, sealer);
  CHECK(p.topic.to_string() == "cam0");
  REQUIRE(sealedKeyId(p.envelope) == key.id);
  CHECK(p.pixels.size() == frame.image.total() + kSealTag);

  const auto got = opened(p.topic, p.envelope, p.pixels, key);
  REQUIRE(got);
  CHECK(same(got->image, frame.image));
  CHECK(got->info.sequence == 7);
  CHECK(got->info.camera == "cam0");

  // Another key, or the same key under another id: nothing opens.
  CHECK_FALSE(opened(p.topic, p.envelope, p.pixels, newFrameKey()));
  FrameKey other_id = key;
  ++other_id.id;
  CHECK_FALSE(opened(p.topic, p.envelope, p.pixels, other_id));
  FrameKey other_key = newFrameKey();
  other_key.id = key.id;
  CHECK_FALSE(opened(p.topic, p.envelope, p.pixels, other_key));
  // The same frame sealed again by the same sealer: under other nonces
  // (bytes 12 to 23), and it opens all the same.
  const Parts again = sealedParts(context, frame, sealer);
  CHECK(std::memcmp(static_cast<const char*>(again.envelope.data()) + 12,
                    static_cast<const char*>(p.envelope.data()) + 12, 12) != 0);
  CHECK(opened(again.topic, again.envelope, again.pixels, key));
  // A plain frame's header names no key.
  const zmq::message_t plain_header(frameHeaderOf(frame).SerializeAsString());
  CHECK_FALSE(sealedKeyId(plain_header));
}

TEST_CASE("A sealed frame changed anywhere, or its parts moved, does not open",
          "[transport][seal]") {
  zmq::context_t context;
  const FrameKey key = newFrameKey();
  FrameSealer sealer(key);
  const Parts a = sealedParts(context, testFrame("cam0", 1, 1), sealer);
  const Parts b = sealedParts(context, testFrame("cam0", 2, 2), sealer);
  REQUIRE(opened(a.topic, a.envelope, a.pixels, key));

  // One bit flipped in each byte position class: nonce, sealed header, tag,
  // pixels.
  for (size_t at : {size_t{12}, size_t{30}, size_t{40}, a.envelope.size() - 1}) {
    CAPTURE(at);
    zmq::message_t changed = copyOf(a.envelope);
    static_cast<unsigned char*>(changed.data())[at] ^= 1;
    CHECK_FALSE(opened(a.topic, changed, a.pixels, key));
  }
  for (size_t at : {size_t{0}, a.pixels.size() / 2, a.pixels.size() - 1}) {
    CAPTURE(at);
    zmq::message_t changed = copyOf(a.pixels);
    static_cast<unsigned char*>(changed.data())[at] ^= 1;
    CHECK_FALSE(opened(a.topic, a.envelope, changed, key));
  }
  // Frame b's pixels under frame a's header, and the other way round.
  CHECK_FALSE(opened(a.topic, a.envelope, b.pixels, key));
  CHECK_FALSE(opened(b.topic, b.envelope, a.pixels, key));
  // Frame a's parts sent as another camera's.
  CHECK_FALSE(opened(zmq::message_t(std::string("cam1")), a.envelope, a.pixels, key));
  // Cut short.
  CHECK_FALSE(opened(a.topic, zmq::message_t(a.envelope.data(), 20), a.pixels, key));
  CHECK_FALSE(opened(a.topic, a.envelope, zmq::message_t(a.pixels.data(), 10), key));
}

TEST_CASE("A CURVE subscriber takes sealed frames once each, with the key it asked",
          "[transport][seal]") {
  test::TempDir dir;
  const CurveKeyPair server_keys = *generateKeyPair();
  const std::string secret = dir.write("server.key_secret", secretKeyFileText(server_keys));
  REQUIRE(::chmod(secret.c_str(), 0600) == 0);
  zmq::context_t context;
  auto curve = CurveServer::start(context, secret, "");
  REQUIRE(curve);
  const FrameKey key = newFrameKey();
  FrameSealer sealer(key);

  // The key's server: a CURVE REP answering FrameKeyRequest (as the video
  // server's control socket does).
  zmq::socket_t control(context, zmq::socket_type::rep);
  control.set(zmq::sockopt::linger, 0);
  (*curve)->secure(control);
  control.bind("tcp://127.0.0.1:*");
  const std::string control_endpoint = control.get(zmq::sockopt::last_endpoint);
  std::atomic<int> asked{0};
  std::atomic<bool> stop{false};
  std::thread answering([&] {
    while (!stop) {
      zmq::pollitem_t item{control.handle(), 0, ZMQ_POLLIN, 0};
      if (zmq::poll(&item, 1, 50ms) == 0) continue;
      zmq::message_t m;
      if (!control.recv(m)) continue;
      proto::ControlRequest request;
      proto::ControlReply reply;
      if (request.ParseFromArray(m.data(), static_cast<int>(m.size())) && request.has_frame_key()) {
        reply.mutable_frame_key()->set_key(key.key.data(), key.key.size());
        reply.mutable_frame_key()->set_key_id(key.id);
        ++asked;
      }
      control.send(zmq::buffer(reply.SerializeAsString()), zmq::send_flags::none);
    }
  });

  zmq::socket_t pub(context, zmq::socket_type::pub);
  pub.set(zmq::sockopt::linger, 0);
  pub.bind("tcp://127.0.0.1:*");
  const CurveClientKeys client{*generateKeyPair(), server_keys.public_key};
  FrameSubscriber sub(context, pub.get(zmq::sockopt::last_endpoint), "cam0", 16, client,
                      control_endpoint);
  CHECK_THROWS_AS(FrameSubscriber(context, "tcp://127.0.0.1:1", "cam0", 4, client),
                  std::invalid_argument);

  // Until the subscription has arrived, frames are dropped: seal frame 1
  // until one comes through.
  std::optional<Frame> first;
  for (int i = 0; i < 100 && !first; ++i) {
    sealer.send(pub, testFrame("cam0", 1, 1));
    first = sub.receive(100ms);
  }
  REQUIRE(first);
  CHECK(same(first->image, testFrame("cam0", 1, 1).image));
  CHECK(asked == 1);
  while (sub.receive(50ms)) {
  }
  const uint64_t malformed_before = sub.malformedMessages();

  // Frame 1 sent again (a recorded frame replayed): skipped.
  sealer.send(pub, testFrame("cam0", 1, 1));
  CHECK_FALSE(sub.receive(300ms));
  CHECK(sub.malformedMessages() == malformed_before + 1);
  // A plain frame to a subscriber that expects sealed ones: skipped.
  sendFrame(pub, testFrame("cam0", 2, 2));
  CHECK_FALSE(sub.receive(300ms));
  CHECK(sub.malformedMessages() == malformed_before + 2);
  // Under another key (a forger's): not opened, and the key server asked
  // at most once a second, whatever the number of such frames.
  const FrameKey forger = newFrameKey();
  FrameSealer forging(forger);
  for (int i = 0; i < 5; ++i) forging.send(pub, testFrame("cam0", 3 + i, 3));
  CHECK_FALSE(sub.receive(300ms));
  CHECK(sub.framesUnopened() == 5);
  CHECK(asked <= 2);  // not once per frame
  // The next frame, sealed with the key: taken (positive control).
  const auto next = [&] {
    sealer.send(pub, testFrame("cam0", 9, 4));
    return sub.receive(2s);
  }();
  REQUIRE(next);
  CHECK(next->info.sequence == 9);
  CHECK(same(next->image, testFrame("cam0", 9, 4).image));

  stop = true;
  answering.join();
}
