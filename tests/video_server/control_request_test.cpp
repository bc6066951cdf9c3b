// Pins the bounds of the control socket's request path: the size limit (in
// the parser and on the socket), non-finite and out-of-range numbers refused
// naming the field, and output frame sizes bounded however they are derived.
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <thread>

#include <catch2/catch.hpp>
#include <zmq.hpp>

#include "picksight/sources/source.hpp"
#include "picksight/transport/control_client.hpp"
#include "picksight/video_server/control_request.hpp"
#include "picksight/video_server/frame_pipeline.hpp"
#include "picksight/video_server/video_errors.hpp"
#include "picksight/video_server/video_server.hpp"

using namespace std::chrono_literals;
namespace proto = picksight::proto;
using picksight::video::decodeRequest;
using picksight::video::VideoErrc;

namespace {

constexpr auto kTimeout = 10s;
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

picksight::Result<proto::ControlRequest> roundTrip(const proto::ControlRequest& request) {
  const std::string bytes = request.SerializeAsString();
  return decodeRequest(bytes.data(), bytes.size());
}

proto::ControlRequest setMode(double fps) {
  proto::ControlRequest r;
  r.mutable_set_mode()->set_camera("cam0");
  r.mutable_set_mode()->set_mode(proto::FREERUN);
  r.mutable_set_mode()->set_fps(fps);
  return r;
}

proto::ControlRequest setScale(double scale) {
  proto::ControlRequest r;
  r.mutable_set_size()->set_camera("cam0");
  r.mutable_set_size()->set_scale(scale);
  return r;
}

proto::ControlRequest setFeature(const std::string& value) {
  proto::ControlRequest r;
  r.mutable_set_feature()->set_camera("cam0");
  r.mutable_set_feature()->set_name("ExposureTime");
  r.mutable_set_feature()->set_value(value);
  return r;
}

// One synthetic full-HD camera in trigger mode, on loopback.
picksight::video::ServerConfig fullHd() {
  picksight::video::ServerConfig config;
  config.frames_endpoint = "tcp://127.0.0.1:*";
  config.control_endpoint = "tcp://127.0.0.1:*";
  picksight::video::CameraConfig cam;
  cam.name = "cam";
  cam.uri = "synthetic:width=1920,height=1080,parts=1";
  cam.mode = picksight::video::AcquisitionMode::kTrigger;
  config.cameras = {cam};
  return config;
}

}  // namespace

TEST_CASE("decodeRequest refuses non-finite and out-of-range numbers naming the field",
          "[video_server][control]") {
  for (double fps : {kNaN, kInf, -kInf, -1.0, 1000.5}) {
    INFO("fps " << fps);
    auto r = roundTrip(setMode(fps));
    REQUIRE_FALSE(r);
    CHECK(r.error().code == VideoErrc::kOutOfRange);
    CHECK_THAT(r.error().message, Catch::Contains("set_mode.fps"));
  }
  CHECK_THAT(roundTrip(setMode(kNaN)).error().message, Catch::Contains("got nan"));
  for (double fps : {0.0, 0.5, 25.0, 1000.0}) CHECK(roundTrip(setMode(fps)));

  for (double scale : {kNaN, kInf, -0.5, 16.5}) {
    INFO("scale " << scale);
    auto r = roundTrip(setScale(scale));
    REQUIRE_FALSE(r);
    CHECK(r.error().code == VideoErrc::kOutOfRange);
    CHECK_THAT(r.error().message, Catch::Contains("set_size.scale"));
  }
  for (double scale : {0.0, 0.25, 16.0}) CHECK(roundTrip(setScale(scale)));

  for (const char* value : {"inf", "-inf", "+INF", "nan", "NaN", "Infinity", "-nan"}) {
    INFO("value " << value);
    auto r = roundTrip(setFeature(value));
    REQUIRE_FALSE(r);
    CHECK(r.error().code == VideoErrc::kOutOfRange);
    CHECK_THAT(r.error().message, Catch::Contains("ExposureTime") && Catch::Contains(value));
  }
  for (const char* value : {"5000", "-2.5", "Continuous", "information", "nano", ""}) {
    INFO("value " << value);
    CHECK(roundTrip(setFeature(value)));
  }
}

TEST_CASE("decodeRequest bounds the message and its strings", "[video_server][control]") {
  const std::string huge(picksight::transport::kMaxControlRequestBytes + 1, '\x0a');
  auto r = decodeRequest(huge.data(), huge.size());
  REQUIRE_FALSE(r);
  CHECK(r.error().code == VideoErrc::kBadRequest);
  CHECK_THAT(r.error().message, Catch::Contains("65537 bytes") && Catch::Contains("65536"));

  proto::ControlRequest named;
  named.mutable_trigger()->set_camera(std::string(257, 'c'));
  r = roundTrip(named);
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains("camera is 257 bytes long"));
  named.mutable_trigger()->set_camera(std::string(256, 'c'));
  CHECK(roundTrip(named));

  r = roundTrip(setFeature(std::string(5000, '1')));
  REQUIRE_FALSE(r);
  CHECK_THAT(r.error().message, Catch::Contains("set_feature.value"));

  const std::string garbage = "\xff\xff\xff\xff";
  CHECK(decodeRequest(garbage.data(), garbage.size()).error().code == VideoErrc::kBadRequest);
  CHECK(decodeRequest(nullptr, 0).error().code == VideoErrc::kBadRequest);
}

TEST_CASE("a control message over the limit is dropped and the server goes on",
          "[video_server][control]") {
  picksight::video::VideoServer server(fullHd());
  server.start();
  zmq::context_t context;
  // ControlClient refuses it itself, saying why.
  picksight::transport::ControlClient client(context, server.controlEndpoint(), 5s);
  proto::ControlRequest big;
  big.mutable_set_feature()->set_camera("cam");
  big.mutable_set_feature()->set_name("Note");
  big.mutable_set_feature()->set_value(std::string(1 << 20, 'x'));
  auto refused = client.call(big);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == picksight::transport::ControlErrc::kBadRequest);
  CHECK_THAT(refused.error().message, Catch::Contains("65536"));

  // A raw client sending it anyway gets nothing back: ZeroMQ drops the
  // message (ZMQ_MAXMSGSIZE) and the connection.
  zmq::socket_t raw(context, zmq::socket_type::req);
  raw.set(zmq::sockopt::linger, 0);
  raw.connect(server.controlEndpoint());
  const std::string bytes = big.SerializeAsString();
  raw.send(zmq::buffer(bytes), zmq::send_flags::none);
  zmq::pollitem_t item{raw.handle(), 0, ZMQ_POLLIN, 0};
  CHECK(zmq::poll(&item, 1, 500ms) == 0);

  // Everyone else is served as before.
  proto::ControlRequest list;
  list.mutable_list_cameras();
  auto listed = client.call(list);
  REQUIRE(listed);
  CHECK(listed->list_cameras().cameras_size() == 1);
}

TEST_CASE("a derived output size over the limit is refused like an explicit one",
          "[video_server][control]") {
  picksight::video::VideoServer server(fullHd());
  server.start();
  proto::ControlRequest describe;
  describe.mutable_describe_camera()->set_camera("cam");
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  while (server.handle(describe).describe_camera().summary().state() != "streaming") {
    REQUIRE(std::chrono::steady_clock::now() < deadline);
    std::this_thread::sleep_for(5ms);
  }
  // `size cam --scale 16` on a full-HD camera: 30720x17280.
  proto::ControlRequest scaled;
  scaled.mutable_set_size()->set_camera("cam");
  scaled.mutable_set_size()->set_scale(16);
  auto reply = server.handle(scaled);
  CHECK(reply.error().code() == proto::Error::OUT_OF_RANGE);
  CHECK_THAT(reply.error().text(), Catch::Contains("30720x17280") && Catch::Contains("16384"));
  // Within the side limit but not the pixel count.
  proto::ControlRequest explicit_size;
  explicit_size.mutable_set_size()->set_camera("cam");
  explicit_size.mutable_set_size()->set_width(16384);
  explicit_size.mutable_set_size()->set_height(16384);
  reply = server.handle(explicit_size);
  CHECK(reply.error().code() == proto::Error::OUT_OF_RANGE);
  CHECK_THAT(reply.error().text(), Catch::Contains("16384x16384"));
  // The camera kept its settings.
  CHECK(server.handle(describe).describe_camera().output_width() == 1920);
  scaled.mutable_set_size()->set_scale(4);
  CHECK(server.handle(scaled).error().code() == proto::Error::OK);
  CHECK(server.handle(describe).describe_camera().output_width() == 7680);
}

TEST_CASE("settings accepted before the sensor was known drop frames they would make too big",
          "[video_server][control]") {
  picksight::video::OutputSettings s;
  s.scale = 16;
  REQUIRE(picksight::video::validateOutputSettings(s, cv::Size()));
  picksight::video::SourceFrame frame;
  frame.image = cv::Mat(1080, 1920, CV_8UC1, cv::Scalar(0));
  frame.layout = picksight::video::PixelLayout::kMono8;
  auto out = picksight::video::applyOutputSettings(frame, s);
  REQUIRE_FALSE(out);
  CHECK(out.error().code == VideoErrc::kOutOfRange);
  CHECK_THAT(out.error().message, Catch::Contains("30720x17280"));
  s.scale = 2;
  CHECK(picksight::video::applyOutputSettings(frame, s));
}

TEST_CASE("decodeRequest checks the hardware trigger's line, edge and timeout",
          "[video_server][control]") {
  proto::ControlRequest r = setMode(0);
  auto* m = r.mutable_set_mode();
  m->set_mode(proto::HARDWARE_TRIGGER);
  m->set_trigger_line("Line1");
  for (const char* edge : {"", "RisingEdge", "FallingEdge", "AnyEdge", "LevelHigh", "LevelLow"}) {
    m->set_trigger_activation(edge);
    CHECK(roundTrip(r));
  }
  m->set_trigger_activation("rising");
  auto edge = roundTrip(r);
  REQUIRE_FALSE(edge);
  CHECK(edge.error().code == VideoErrc::kOutOfRange);
  CHECK_THAT(edge.error().message,
             Catch::Contains("set_mode.trigger_activation") && Catch::Contains("'rising'"));
  m->set_trigger_activation("");
  m->set_trigger_timeout_ms(3600001);
  auto timeout = roundTrip(r);
  REQUIRE_FALSE(timeout);
  CHECK_THAT(timeout.error().message, Catch::Contains("set_mode.trigger_timeout_ms"));
  m->set_trigger_timeout_ms(3600000);
  CHECK(roundTrip(r));
  m->set_trigger_line(std::string(300, 'L'));
  auto line = roundTrip(r);
  REQUIRE_FALSE(line);
  CHECK_THAT(line.error().message, Catch::Contains("set_mode.trigger_line"));
}
