// Pins the frame wire format: header/payload consistency, the zero-copy
// decode, the encoder and decoder agreeing, and a FrameSubscriber that returns
// only well-formed frames of exactly its camera and counts the malformed ones.
#include <chrono>
#include <cstring>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <zmq.hpp>

#include "picksight/transport/frame_message.hpp"

using namespace std::chrono_literals;
namespace proto = picksight::proto;
using picksight::Frame;
using picksight::transport::FrameSubscriber;

namespace {

constexpr auto kTimeout = 10000ms;
// Sequence numbers of the probe frames that wait for the subscription to reach
// the publisher; the frames under test use small numbers.
constexpr uint64_t kProbeBase = 1000000;

proto::FrameHeader monoHeader(const std::string& camera, uint64_t sequence, uint32_t width,
                              uint32_t height, uint32_t stride) {
  proto::FrameHeader h;
  h.set_camera(camera);
  h.set_sequence(sequence);
  h.set_width(width);
  h.set_height(height);
  h.set_stride(stride);
  h.set_pixel_format(proto::MONO8);
  h.set_scale_x(1);
  h.set_scale_y(1);
  return h;
}

// Pixel bytes whose value encodes their offset.
std::string pattern(size_t size) {
  std::string bytes(size, '\0');
  for (size_t i = 0; i < size; ++i) bytes[i] = static_cast<char>(i * 7 + 1);
  return bytes;
}

void sendParts(zmq::socket_t& pub, const std::vector<std::string>& parts) {
  for (size_t i = 0; i < parts.size(); ++i) {
    pub.send(zmq::buffer(parts[i]),
             i + 1 < parts.size() ? zmq::send_flags::sndmore : zmq::send_flags::none);
  }
}

void sendFrame(zmq::socket_t& pub, const std::string& topic, const proto::FrameHeader& header,
               const std::string& pixels) {
  sendParts(pub, {topic, header.SerializeAsString(), pixels});
}

// Sends probe frames until the subscriber receives one, so that everything
// sent afterwards reaches it (PUB drops messages for unknown subscriptions).
void waitForSubscription(zmq::socket_t& pub, FrameSubscriber& sub, const std::string& topic) {
  for (uint64_t i = 0; i < 100; ++i) {
    sendFrame(pub, topic, monoHeader(topic, kProbeBase + i, 2, 2, 2), pattern(4));
    if (sub.receive(100ms)) return;
  }
  FAIL("the subscription never reached the publisher");
}

// The next frame that is not a probe.
std::optional<Frame> receiveNonProbe(FrameSubscriber& sub) {
  for (;;) {
    auto frame = sub.receive(kTimeout);
    if (!frame || frame->info.sequence < kProbeBase) return frame;
  }
}

}  // namespace

TEST_CASE("bytesPerPixel knows mono8 and bgr8 only", "[common]") {
  CHECK(picksight::transport::bytesPerPixel(proto::MONO8) == 1);
  CHECK(picksight::transport::bytesPerPixel(proto::BGR8) == 3);
  CHECK(picksight::transport::bytesPerPixel(proto::PIXEL_FORMAT_UNSPECIFIED) == 0);
}

TEST_CASE("frameIsConsistent checks format, sizes, stride and payload length", "[common]") {
  using picksight::transport::frameIsConsistent;
  const auto h = monoHeader("cam", 1, 4, 3, 4);
  CHECK(frameIsConsistent(h, 12));
  CHECK(frameIsConsistent(h, 20));  // trailing bytes are harmless
  CHECK_FALSE(frameIsConsistent(h, 11));
  CHECK_FALSE(frameIsConsistent(h, 0));
  auto padded = monoHeader("cam", 1, 4, 3, 8);
  CHECK(frameIsConsistent(padded, 24));
  CHECK_FALSE(frameIsConsistent(padded, 12));
  auto narrow = monoHeader("cam", 1, 4, 3, 3);  // stride below width
  CHECK_FALSE(frameIsConsistent(narrow, 100));
  auto bgr = monoHeader("cam", 1, 4, 3, 12);
  bgr.set_pixel_format(proto::BGR8);
  CHECK(frameIsConsistent(bgr, 36));
  bgr.set_stride(11);  // 4 pixels of 3 bytes do not fit in 11
  CHECK_FALSE(frameIsConsistent(bgr, 100));
  auto unknown = h;
  unknown.set_pixel_format(proto::PIXEL_FORMAT_UNSPECIFIED);
  CHECK_FALSE(frameIsConsistent(unknown, 12));
  auto empty = monoHeader("cam", 1, 0, 3, 4);
  CHECK_FALSE(frameIsConsistent(empty, 12));
  auto flat = monoHeader("cam", 1, 4, 0, 4);
  CHECK_FALSE(frameIsConsistent(flat, 12));
}

TEST_CASE("decodeFrame image is a view on the pixel bytes with the stride", "[common]") {
  // Trailing bytes make the message large enough that ZeroMQ keeps its bytes
  // outside the message_t object (small ones move with it).
  const std::string bytes = pattern(64);
  zmq::message_t mono_pixels(bytes.data(), bytes.size());
  const void* mono_data = mono_pixels.data();
  const auto frame =
      picksight::transport::decodeFrame(monoHeader("cam", 1, 3, 2, 4), std::move(mono_pixels));
  REQUIRE(frame);
  const cv::Mat image = frame->image;
  REQUIRE(image.type() == CV_8UC1);
  REQUIRE(image.cols == 3);
  REQUIRE(image.rows == 2);
  CHECK(image.step[0] == 4);
  CHECK(image.data == mono_data);
  CHECK(image.at<uint8_t>(1, 2) == static_cast<uint8_t>(bytes[1 * 4 + 2]));

  auto colour_header = monoHeader("cam", 1, 2, 2, 6);
  colour_header.set_pixel_format(proto::BGR8);
  const std::string bgr = pattern(12);
  const auto colour =
      picksight::transport::decodeFrame(colour_header, zmq::message_t(bgr.data(), bgr.size()));
  REQUIRE(colour);
  const cv::Mat c = colour->image;
  REQUIRE(c.type() == CV_8UC3);
  CHECK(c.at<cv::Vec3b>(1, 1)[2] == static_cast<uint8_t>(bgr[6 + 3 + 2]));
}

TEST_CASE("decodeFrame refuses an inconsistent header and fills the mapping", "[common]") {
  const std::string bytes = pattern(12);
  CHECK_FALSE(picksight::transport::decodeFrame(monoHeader("cam", 1, 4, 3, 4),
                                                zmq::message_t(bytes.data(), 11)));
  auto h = monoHeader("cam", 9, 4, 3, 4);
  h.set_roi_x(10);
  h.set_roi_y(20);
  h.set_scale_x(0.5);
  h.set_scale_y(0);  // left out by the sender: no resize
  h.set_triggered(true);
  h.set_host_timestamp_ns(123);
  auto* t = h.add_truth();
  t->set_type("disc");
  t->set_x(1.5);
  t->set_symmetry_deg(0);
  const auto frame =
      picksight::transport::decodeFrame(h, zmq::message_t(bytes.data(), bytes.size()));
  REQUIRE(frame);
  CHECK(frame->mapping.roi_x == 10);
  CHECK(frame->mapping.roi_y == 20);
  CHECK(frame->mapping.scale_x == 0.5);
  CHECK(frame->mapping.scale_y == 1.0);
  CHECK(frame->info.camera == "cam");
  CHECK(frame->info.sequence == 9);
  CHECK(frame->info.width == 4);
  CHECK(frame->info.height == 3);
  CHECK(frame->info.triggered);
  CHECK(frame->info.host_timestamp_ns == 123);
  REQUIRE(frame->truth.size() == 1);
  CHECK(frame->truth[0].type == "disc");
  CHECK(frame->truth[0].x == 1.5);
  CHECK(frame->truth[0].symmetry_deg == 0);
}

TEST_CASE("A frame survives encoding and decoding and outlives its sender's image", "[common]") {
  zmq::context_t context;
  zmq::socket_t pub(context, zmq::socket_type::pub);
  pub.set(zmq::sockopt::linger, 0);
  pub.bind("tcp://127.0.0.1:*");
  FrameSubscriber sub(context, pub.get(zmq::sockopt::last_endpoint), "cam1", 64);
  waitForSubscription(pub, sub, "cam1");

  Frame sent;
  cv::Mat sensor(40, 60, CV_8UC3);
  cv::randu(sensor, 0, 255);
  sent.image = sensor(cv::Rect(5, 7, 30, 20));  // a view: not continuous
  sent.mapping = {100, 50, 0.5, 0.25};
  sent.info.camera = "cam1";
  sent.info.sequence = 3;
  sent.info.device_timestamp_ns = 11;
  sent.info.host_timestamp_ns = 22;
  sent.info.triggered = true;
  sent.info.compressed = true;
  sent.truth.push_back({"ring", 1, 2, 30, 180, 400});
  const cv::Mat expected = sent.image.clone();
  picksight::transport::sendFrame(pub, sent);
  sent = Frame{};
  sensor.release();

  const auto got = receiveNonProbe(sub);
  REQUIRE(got);
  CHECK(got->info.camera == "cam1");
  CHECK(got->info.sequence == 3);
  CHECK(got->info.device_timestamp_ns == 11);
  CHECK(got->info.host_timestamp_ns == 22);
  CHECK(got->info.triggered);
  CHECK(got->info.compressed);
  CHECK(got->info.received_ns > 0);
  CHECK(got->info.width == 30);
  CHECK(got->info.height == 20);
  CHECK(got->mapping.roi_x == 100);
  CHECK(got->mapping.roi_y == 50);
  CHECK(got->mapping.scale_x == 0.5);
  CHECK(got->mapping.scale_y == 0.25);
  REQUIRE(got->truth.size() == 1);
  CHECK(got->truth[0].type == "ring");
  CHECK(got->truth[0].angle_deg == 30);
  CHECK(got->truth[0].symmetry_deg == 180);
  CHECK(got->truth[0].area_px == 400);
  REQUIRE(got->image.type() == CV_8UC3);
  CHECK(cv::norm(got->image, expected, cv::NORM_INF) == 0);

  // The image stays valid as long as a copy of the frame holds its owner.
  const cv::Mat view = got->image;
  const auto owner = got->owner;
  CHECK(owner != nullptr);
  CHECK(cv::norm(view, expected, cv::NORM_INF) == 0);
}

TEST_CASE("FrameSubscriber returns only well-formed frames of its camera", "[common]") {
  zmq::context_t context;
  zmq::socket_t pub(context, zmq::socket_type::pub);
  pub.set(zmq::sockopt::linger, 0);
  pub.bind("tcp://127.0.0.1:*");
  const std::string endpoint = pub.get(zmq::sockopt::last_endpoint);
  REQUIRE(endpoint.rfind("tcp://127.0.0.1:", 0) == 0);

  // A deep queue: this test checks filtering, not loss under load.
  FrameSubscriber sub(context, endpoint, "cam1", 64);
  waitForSubscription(pub, sub, "cam1");
  const uint64_t malformed_before = sub.malformedMessages();
  CHECK(malformed_before == 0);

  const auto good = monoHeader("cam1", 1, 5, 4, 6);
  const std::string good_pixels = pattern(24);
  // Malformed: two parts only.
  sendParts(pub, {"cam1", good.SerializeAsString()});
  // Malformed: a header that is not a FrameHeader.
  sendParts(pub, {"cam1", std::string("\xff\xff\xff\xff", 4), good_pixels});
  // Malformed: payload shorter than stride * height.
  sendFrame(pub, "cam1", good, good_pixels.substr(0, 23));
  // Malformed: a header with no pixel format.
  auto no_format = good;
  no_format.set_pixel_format(proto::PIXEL_FORMAT_UNSPECIFIED);
  sendFrame(pub, "cam1", no_format, good_pixels);
  // Malformed: four parts.
  sendParts(pub, {"cam1", good.SerializeAsString(), good_pixels, "extra"});
  // Well-formed, but for another camera whose name starts with ours.
  sendFrame(pub, "cam10", monoHeader("cam10", 7, 5, 4, 6), good_pixels);
  // The one valid frame, then another camera again, then an end marker.
  sendFrame(pub, "cam1", good, good_pixels);
  sendFrame(pub, "cam10", monoHeader("cam10", 8, 5, 4, 6), good_pixels);
  sendFrame(pub, "cam1", monoHeader("cam1", 2, 2, 2, 2), pattern(4));

  auto frame = receiveNonProbe(sub);
  REQUIRE(frame);
  CHECK(frame->info.camera == "cam1");
  CHECK(frame->info.sequence == 1);
  CHECK(frame->info.width == 5);
  CHECK(frame->info.height == 4);
  CHECK(frame->info.received_ns > 0);
  REQUIRE(frame->image.step[0] * static_cast<size_t>(frame->image.rows) == good_pixels.size());
  CHECK(std::memcmp(frame->image.data, good_pixels.data(), good_pixels.size()) == 0);
  CHECK(frame->image.at<uint8_t>(3, 4) == static_cast<uint8_t>(good_pixels[3 * 6 + 4]));

  auto marker = receiveNonProbe(sub);
  REQUIRE(marker);
  CHECK(marker->info.camera == "cam1");
  CHECK(marker->info.sequence == 2);
  CHECK(sub.malformedMessages() - malformed_before == 5);
  CHECK_FALSE(sub.receive(50ms));
}

TEST_CASE("FrameSubscriber with an empty camera name receives every camera", "[common]") {
  zmq::context_t context;
  zmq::socket_t pub(context, zmq::socket_type::pub);
  pub.set(zmq::sockopt::linger, 0);
  pub.bind("tcp://127.0.0.1:*");
  FrameSubscriber sub(context, pub.get(zmq::sockopt::last_endpoint), "", 64);
  waitForSubscription(pub, sub, "cam1");
  sendFrame(pub, "cam1", monoHeader("cam1", 1, 2, 2, 2), pattern(4));
  sendFrame(pub, "cam10", monoHeader("cam10", 2, 2, 2, 2), pattern(4));
  sendFrame(pub, "other", monoHeader("other", 3, 2, 2, 2), pattern(4));
  for (const char* camera : {"cam1", "cam10", "other"}) {
    auto frame = receiveNonProbe(sub);
    REQUIRE(frame);
    CHECK(frame->info.camera == camera);
  }
  CHECK(sub.malformedMessages() == 0);
}

TEST_CASE("FrameSubscriber receive times out with nothing published", "[common]") {
  zmq::context_t context;
  zmq::socket_t pub(context, zmq::socket_type::pub);
  pub.set(zmq::sockopt::linger, 0);
  pub.bind("tcp://127.0.0.1:*");
  FrameSubscriber sub(context, pub.get(zmq::sockopt::last_endpoint), "cam1");
  CHECK_FALSE(sub.receive(50ms));
  CHECK(sub.malformedMessages() == 0);
}
