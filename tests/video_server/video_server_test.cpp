// Pins the video server in-process: control requests answered by handle()
// and through a real ControlClient, and frames received by a real
// FrameSubscriber whose headers describe the pixels they carry.
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <zmq.hpp>

#include "picksight/transport/control_client.hpp"
#include "picksight/transport/frame_message.hpp"
#include "picksight/video_server/video_server.hpp"

using namespace std::chrono_literals;
namespace proto = picksight::proto;
using picksight::video::AcquisitionMode;
using picksight::video::CameraConfig;
using picksight::video::ServerConfig;
using picksight::video::VideoServer;

namespace {

constexpr auto kTimeout = 10s;

// Two cameras whose names share a prefix, as topics do: "cam1" triggered,
// "cam10" free-running.
ServerConfig testConfig() {
  ServerConfig config;
  config.frames_endpoint = "tcp://127.0.0.1:*";
  config.control_endpoint = "tcp://127.0.0.1:*";
  CameraConfig cam1;
  cam1.name = "cam1";
  // Noise-free: every frame of cam1 holds the same pixels, so a transformed
  // frame can be checked against the full one pixel for pixel.
  cam1.uri = "synthetic:width=320,height=240,parts=3,size=40,seed=7,noise=0";
  cam1.mode = AcquisitionMode::kTrigger;
  CameraConfig cam10;
  cam10.name = "cam10";
  cam10.uri = "synthetic:width=160,height=120,parts=1,size=30";
  cam10.mode = AcquisitionMode::kFreeRun;
  cam10.fps = 20;
  config.cameras = {cam1, cam10};
  return config;
}

proto::ControlRequest describe(const std::string& camera) {
  proto::ControlRequest r;
  r.mutable_describe_camera()->set_camera(camera);
  return r;
}

proto::ControlRequest setRoi(const std::string& camera, uint32_t x, uint32_t y, uint32_t w,
                             uint32_t h) {
  proto::ControlRequest r;
  auto* s = r.mutable_set_roi();
  s->set_camera(camera);
  s->mutable_roi()->set_x(x);
  s->mutable_roi()->set_y(y);
  s->mutable_roi()->set_width(w);
  s->mutable_roi()->set_height(h);
  return r;
}

proto::ControlRequest trigger(const std::string& camera) {
  proto::ControlRequest r;
  r.mutable_trigger()->set_camera(camera);
  return r;
}

proto::ControlRequest statistics(const std::string& camera) {
  proto::ControlRequest r;
  r.mutable_statistics()->set_camera(camera);
  return r;
}

// Waits until every camera has opened its source (the sensor size is known).
void waitStreaming(VideoServer& server) {
  for (const char* name : {"cam1", "cam10"}) {
    const auto deadline = std::chrono::steady_clock::now() + kTimeout;
    while (server.handle(describe(name)).describe_camera().summary().state() != "streaming") {
      REQUIRE(std::chrono::steady_clock::now() < deadline);
      std::this_thread::sleep_for(5ms);
    }
  }
}

// Triggers cam1 until the subscriber has a frame: the subscription has then
// reached the publisher and nothing sent later is lost to it.
void waitForSubscription(picksight::transport::ControlClient& control,
                         picksight::transport::FrameSubscriber& sub) {
  for (int i = 0; i < 50; ++i) {
    REQUIRE(control.call(trigger("cam1")));
    if (sub.receive(200ms)) return;
  }
  FAIL("no frame reached the subscriber");
}

// The cam1 frame with exactly this sequence (earlier ones are skipped).
std::optional<picksight::Frame> receiveSequence(picksight::transport::FrameSubscriber& sub,
                                                uint64_t sequence) {
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  while (std::chrono::steady_clock::now() < deadline) {
    auto frame = sub.receive(1000ms);
    if (frame && frame->info.sequence >= sequence) {
      if (frame->info.sequence == sequence) return frame;
      return std::nullopt;
    }
  }
  return std::nullopt;
}

void checkConsistent(const picksight::Frame& f) {
  const cv::Mat& image = f.image;
  const int bpp = image.type() == CV_8UC3 ? 3 : 1;
  CHECK((image.type() == CV_8UC1 || image.type() == CV_8UC3));
  CHECK(image.step[0] >= f.info.width * bpp);
  // Published dense: the decoded view spans rows of exactly the stride.
  CHECK(image.isContinuous());
  CHECK(image.cols == static_cast<int>(f.info.width));
  CHECK(image.rows == static_cast<int>(f.info.height));
  CHECK(image.channels() == bpp);
  CHECK(f.info.host_timestamp_ns > 0);
}

}  // namespace

TEST_CASE("VideoServer binds its endpoints to resolved ports", "[video_server]") {
  VideoServer server(testConfig());
  CHECK_THAT(server.framesEndpoint(), Catch::StartsWith("tcp://127.0.0.1:"));
  CHECK_THAT(server.controlEndpoint(), Catch::StartsWith("tcp://127.0.0.1:"));
  CHECK_THAT(server.framesEndpoint(), !Catch::EndsWith("*"));
  CHECK_THAT(server.controlEndpoint(), !Catch::EndsWith("*"));
  CHECK(server.framesEndpoint() != server.controlEndpoint());
}

TEST_CASE("VideoServer construction errors name the camera or the endpoint", "[video_server]") {
  SECTION("bad source") {
    ServerConfig config = testConfig();
    config.cameras[1].uri = "gige:nothing";
    try {
      VideoServer server(config);
      FAIL("accepted a bad source");
    } catch (const std::runtime_error& e) {
      CHECK_THAT(e.what(), Catch::Contains("cam10") && Catch::Contains("gige"));
    }
  }
  SECTION("bad frames endpoint") {
    ServerConfig config = testConfig();
    config.frames_endpoint = "bogus://nowhere";
    try {
      VideoServer server(config);
      FAIL("accepted a bad endpoint");
    } catch (const std::runtime_error& e) {
      CHECK_THAT(e.what(), Catch::Contains("bogus://nowhere"));
    }
  }
  SECTION("control endpoint already in use") {
    VideoServer first(testConfig());
    ServerConfig config = testConfig();
    config.control_endpoint = first.controlEndpoint();
    try {
      VideoServer server(config);
      FAIL("bound an endpoint already in use");
    } catch (const std::runtime_error& e) {
      CHECK_THAT(e.what(), Catch::Contains(first.controlEndpoint()));
    }
  }
}

TEST_CASE("VideoServer handle lists and describes cameras", "[video_server]") {
  VideoServer server(testConfig());
  server.start();
  waitStreaming(server);

  proto::ControlRequest list;
  list.mutable_list_cameras();
  const auto listed = server.handle(list);
  CHECK(listed.error().code() == proto::Error::OK);
  REQUIRE(listed.list_cameras().cameras_size() == 2);
  CHECK(listed.list_cameras().cameras(0).name() == "cam1");
  CHECK(listed.list_cameras().cameras(0).mode() == proto::TRIGGER);
  CHECK(listed.list_cameras().cameras(0).source() == testConfig().cameras[0].uri);
  CHECK(listed.list_cameras().cameras(1).name() == "cam10");
  CHECK(listed.list_cameras().cameras(1).mode() == proto::FREERUN);

  const auto described = server.handle(describe("cam1"));
  CHECK(described.error().code() == proto::Error::OK);
  const auto& d = described.describe_camera();
  CHECK(d.summary().name() == "cam1");
  CHECK(d.summary().state() == "streaming");
  CHECK(d.vendor() == "PickSight");
  CHECK(d.model() == "synthetic");
  CHECK(d.sensor_width() == 320);
  CHECK(d.sensor_height() == 240);
  CHECK(d.roi().x() == 0);
  CHECK(d.roi().y() == 0);
  CHECK(d.roi().width() == 320);
  CHECK(d.roi().height() == 240);
  CHECK(d.output_width() == 320);
  CHECK(d.output_height() == 240);
  CHECK(d.pixel_format() == proto::MONO8);
  CHECK(d.source_formats_size() > 0);
}

TEST_CASE("VideoServer handle answers an unknown camera with UNKNOWN_CAMERA", "[video_server]") {
  VideoServer server(testConfig());
  for (const auto& request : {describe("cam2"), setRoi("cam2", 0, 0, 10, 10), trigger("cam2"),
                              statistics("cam2"), describe("cam")}) {
    INFO(request.ShortDebugString());
    const auto reply = server.handle(request);
    CHECK(reply.error().code() == proto::Error::UNKNOWN_CAMERA);
    CHECK_THAT(reply.error().text(), Catch::Contains("'cam"));
  }
}

TEST_CASE("VideoServer handle set_roi beyond the sensor is OUT_OF_RANGE", "[video_server]") {
  VideoServer server(testConfig());
  server.start();
  waitStreaming(server);

  auto reply = server.handle(setRoi("cam1", 300, 0, 100, 100));
  CHECK(reply.error().code() == proto::Error::OUT_OF_RANGE);
  CHECK_THAT(reply.error().text(), Catch::Contains("320x240"));
  // uint32 values that do not fit an int, or whose sum does not.
  reply = server.handle(setRoi("cam1", 2000000000u, 0, 2000000000u, 10));
  CHECK(reply.error().code() == proto::Error::OUT_OF_RANGE);
  reply = server.handle(setRoi("cam1", 0, 0, 4000000000u, 10));
  CHECK(reply.error().code() == proto::Error::OUT_OF_RANGE);
  reply = server.handle(setRoi("cam1", 0, 0, 100, 0));
  CHECK(reply.error().code() == proto::Error::OUT_OF_RANGE);
  // Nothing of it was applied.
  CHECK(server.handle(describe("cam1")).describe_camera().roi().width() == 320);

  reply = server.handle(setRoi("cam1", 20, 10, 200, 100));
  CHECK(reply.error().code() == proto::Error::OK);
  auto d = server.handle(describe("cam1")).describe_camera();
  CHECK(d.roi().x() == 20);
  CHECK(d.roi().y() == 10);
  CHECK(d.roi().width() == 200);
  CHECK(d.output_width() == 200);
  CHECK(d.output_height() == 100);

  // Width and height 0: back to the full sensor.
  reply = server.handle(setRoi("cam1", 0, 0, 0, 0));
  CHECK(reply.error().code() == proto::Error::OK);
  d = server.handle(describe("cam1")).describe_camera();
  CHECK(d.roi().width() == 320);
  CHECK(d.roi().height() == 240);
}

TEST_CASE("VideoServer handle rejects out-of-range size, format and mode", "[video_server]") {
  VideoServer server(testConfig());
  server.start();
  waitStreaming(server);

  proto::ControlRequest size;
  size.mutable_set_size()->set_camera("cam1");
  size.mutable_set_size()->set_width(100);
  CHECK(server.handle(size).error().code() == proto::Error::OUT_OF_RANGE);
  size.mutable_set_size()->set_width(0);
  size.mutable_set_size()->set_scale(-2);
  CHECK(server.handle(size).error().code() == proto::Error::OUT_OF_RANGE);

  proto::ControlRequest format;
  format.mutable_set_format()->set_camera("cam1");
  format.mutable_set_format()->set_pixel_format(proto::PIXEL_FORMAT_UNSPECIFIED);
  CHECK(server.handle(format).error().code() == proto::Error::OUT_OF_RANGE);

  proto::ControlRequest mode;
  mode.mutable_set_mode()->set_camera("cam1");
  mode.mutable_set_mode()->set_mode(proto::ACQUISITION_MODE_UNSPECIFIED);
  CHECK(server.handle(mode).error().code() == proto::Error::OUT_OF_RANGE);
  mode.mutable_set_mode()->set_mode(proto::FREERUN);
  mode.mutable_set_mode()->set_fps(-5);
  CHECK(server.handle(mode).error().code() == proto::Error::OUT_OF_RANGE);

  CHECK(server.handle(proto::ControlRequest{}).error().code() == proto::Error::NOT_SUPPORTED);

  // A synthetic camera has no trigger input: said, and the mode unchanged.
  mode.mutable_set_mode()->set_fps(0);
  mode.mutable_set_mode()->set_mode(proto::HARDWARE_TRIGGER);
  const proto::ControlReply hardware = server.handle(mode);
  CHECK(hardware.error().code() == proto::Error::NOT_SUPPORTED);
  CHECK_THAT(hardware.error().text(), Catch::Contains("no hardware trigger input"));
  proto::ControlRequest describe;
  describe.mutable_describe_camera()->set_camera("cam1");
  CHECK(server.handle(describe).describe_camera().summary().mode() != proto::HARDWARE_TRIGGER);
}

TEST_CASE("VideoServer refuses a configured hardware trigger on a camera without one",
          "[video_server]") {
  ServerConfig config = testConfig();
  config.cameras[1].mode = picksight::video::AcquisitionMode::kHardwareTrigger;
  try {
    VideoServer server(config);
    FAIL("accepted a hardware trigger on a synthetic camera");
  } catch (const std::runtime_error& e) {
    CHECK_THAT(e.what(), Catch::Contains("cam10") && Catch::Contains("hardware trigger"));
  }
}

TEST_CASE("VideoServer handle statistics counts each camera's frames", "[video_server]") {
  VideoServer server(testConfig());
  server.start();
  waitStreaming(server);
  uint64_t last_ticket = 0;
  for (int i = 0; i < 3; ++i) {
    const auto reply = server.handle(trigger("cam1"));
    REQUIRE(reply.error().code() == proto::Error::OK);
    CHECK(reply.trigger().triggered());
    last_ticket = reply.trigger().sequence();
  }
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  proto::CameraStatistics cam1;
  do {
    const auto reply = server.handle(statistics("cam1"));
    REQUIRE(reply.error().code() == proto::Error::OK);
    REQUIRE(reply.statistics().cameras_size() == 1);
    cam1 = reply.statistics().cameras(0);
    if (cam1.frames_published() >= 3 && cam1.frames_acquired() >= 3) break;
    std::this_thread::sleep_for(5ms);
  } while (std::chrono::steady_clock::now() < deadline);
  CHECK(cam1.camera() == "cam1");
  CHECK(cam1.frames_acquired() == 3);
  CHECK(cam1.frames_published() == 3);
  CHECK(cam1.last_sequence() == last_ticket);
  CHECK(cam1.acquisition_errors() == 0);

  const auto all = server.handle(statistics(""));
  REQUIRE(all.statistics().cameras_size() == 2);
  CHECK(all.statistics().cameras(0).camera() == "cam1");
  CHECK(all.statistics().cameras(1).camera() == "cam10");
}

TEST_CASE("VideoServer answers a real ControlClient on its bound endpoint", "[video_server]") {
  VideoServer server(testConfig());
  server.start();
  zmq::context_t context;
  picksight::transport::ControlClient client(context, server.controlEndpoint(), 10000ms);

  proto::ControlRequest list;
  list.mutable_list_cameras();
  auto listed = client.call(list);
  REQUIRE(listed);
  CHECK(listed->list_cameras().cameras_size() == 2);

  auto unknown = client.call(describe("nope"));
  REQUIRE_FALSE(unknown);
  CHECK(unknown.error().code == picksight::transport::ControlErrc::kUnknownCamera);
  CHECK_THAT(unknown.error().message, Catch::Contains("nope"));

  auto first = client.call(trigger("cam1"));
  auto second = client.call(trigger("cam1"));
  REQUIRE(first);
  REQUIRE(second);
  CHECK(first->trigger().triggered());
  CHECK(second->trigger().sequence() == first->trigger().sequence() + 1);

  // An empty or undecodable request gets BAD_REQUEST, and the socket goes on.
  CHECK(client.call(proto::ControlRequest{}).error().code ==
        picksight::transport::ControlErrc::kBadRequest);
  {
    zmq::socket_t raw(context, zmq::socket_type::req);
    raw.set(zmq::sockopt::linger, 0);
    raw.set(zmq::sockopt::rcvtimeo, 10000);
    raw.connect(server.controlEndpoint());
    raw.send(zmq::buffer(std::string("\xff\xff\xff", 3)), zmq::send_flags::none);
    zmq::message_t reply_bytes;
    REQUIRE(raw.recv(reply_bytes));
    proto::ControlReply reply;
    REQUIRE(reply.ParseFromArray(reply_bytes.data(), static_cast<int>(reply_bytes.size())));
    CHECK(reply.error().code() == proto::Error::BAD_REQUEST);
  }
  CHECK(client.call(list));
}

TEST_CASE("VideoServer frames reach a FrameSubscriber with consistent headers", "[video_server]") {
  VideoServer server(testConfig());
  server.start();
  zmq::context_t context;
  picksight::transport::ControlClient control(context, server.controlEndpoint(), 10000ms);
  picksight::transport::FrameSubscriber sub(context, server.framesEndpoint(), "cam1", 16);
  waitForSubscription(control, sub);

  SECTION("full sensor, mono") {
    auto ticket = control.call(trigger("cam1"));
    REQUIRE(ticket);
    auto frame = receiveSequence(sub, ticket->trigger().sequence());
    REQUIRE(frame);
    const auto& h = frame->info;
    const auto& m = frame->mapping;
    CHECK(h.camera == "cam1");
    CHECK(h.width == 320);
    CHECK(h.height == 240);
    CHECK(frame->image.step[0] == 320);
    CHECK(frame->image.type() == CV_8UC1);
    CHECK(m.roi_x == 0);
    CHECK(m.roi_y == 0);
    CHECK(m.scale_x == 1.0);
    CHECK(m.scale_y == 1.0);
    CHECK(h.triggered);
    REQUIRE(frame->truth.size() == 3);
    for (const auto& t : frame->truth) {
      CHECK_FALSE(t.type.empty());
      CHECK(t.area_px > 0);
      CHECK(t.x > 0);
      CHECK(t.x < 320);
    }
    checkConsistent(*frame);
  }

  SECTION("ROI, scale and bgr") {
    auto full_ticket = control.call(trigger("cam1"));
    REQUIRE(full_ticket);
    const auto full = receiveSequence(sub, full_ticket->trigger().sequence());
    REQUIRE(full);
    REQUIRE(full->info.width == 320);
    REQUIRE(control.call(setRoi("cam1", 10, 20, 200, 100)));
    proto::ControlRequest size;
    size.mutable_set_size()->set_camera("cam1");
    size.mutable_set_size()->set_scale(0.5);
    REQUIRE(control.call(size));
    proto::ControlRequest format;
    format.mutable_set_format()->set_camera("cam1");
    format.mutable_set_format()->set_pixel_format(proto::BGR8);
    REQUIRE(control.call(format));

    auto ticket = control.call(trigger("cam1"));
    REQUIRE(ticket);
    auto frame = receiveSequence(sub, ticket->trigger().sequence());
    REQUIRE(frame);
    const auto& h = frame->info;
    const auto& m = frame->mapping;
    CHECK(h.width == 100);
    CHECK(h.height == 50);
    CHECK(frame->image.step[0] == 300);
    CHECK(frame->image.type() == CV_8UC3);
    CHECK(m.roi_x == 10);
    CHECK(m.roi_y == 20);
    CHECK(m.scale_x == 0.5);
    CHECK(m.scale_y == 0.5);
    // The pixels are the sensor's region, halved and in colour.
    cv::Mat expected;
    cv::resize(full->image(cv::Rect(10, 20, 200, 100)), expected, cv::Size(100, 50), 0, 0,
               cv::INTER_AREA);
    cv::cvtColor(expected, expected, cv::COLOR_GRAY2BGR);
    CHECK(cv::norm(frame->image, expected, cv::NORM_INF) <= 1);
    // Truth stays in sensor pixels, whatever the output transform.
    REQUIRE(frame->truth.size() == 3);
    for (size_t i = 0; i < 3; ++i) {
      CHECK(frame->truth[i].x == full->truth[i].x);
      CHECK(frame->truth[i].y == full->truth[i].y);
    }
    checkConsistent(*frame);
  }

  // cam10 publishes all along; its topic starts with "cam1" but its frames
  // must never reach a cam1 subscriber.
  for (int i = 0; i < 5; ++i) {
    auto ticket = control.call(trigger("cam1"));
    REQUIRE(ticket);
    auto frame = receiveSequence(sub, ticket->trigger().sequence());
    REQUIRE(frame);
    CHECK(frame->info.camera == "cam1");
  }
  CHECK(sub.malformedMessages() == 0);
}

TEST_CASE("VideoServer frames of a free-running camera arrive in order", "[video_server]") {
  VideoServer server(testConfig());
  server.start();
  zmq::context_t context;
  picksight::transport::FrameSubscriber sub(context, server.framesEndpoint(), "cam10", 16);
  uint64_t previous = 0;
  int received = 0;
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  while (received < 5 && std::chrono::steady_clock::now() < deadline) {
    auto frame = sub.receive(1000ms);
    if (!frame) continue;
    CHECK(frame->info.camera == "cam10");
    CHECK(frame->info.sequence > previous);
    CHECK_FALSE(frame->info.triggered);
    CHECK(frame->info.width == 160);
    CHECK(frame->truth.size() == 1);
    checkConsistent(*frame);
    previous = frame->info.sequence;
    ++received;
  }
  CHECK(received == 5);
}
