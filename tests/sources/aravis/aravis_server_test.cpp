// Pins an Aravis camera behind a real picksight-video-server process, as a
// client sees it: describe, features over the control socket, free-run and
// triggered frames, the server's ROI, Bayer frames standardized, and frames
// resuming on the same topic after the camera was killed and restarted.
#include <catch2/catch.hpp>

#include <thread>
#include <zmq.hpp>

#include "cell_fixture.hpp"
#include "fake_gv_camera.hpp"
#include "picksight/transport/control_client.hpp"
#include "picksight/transport/frame_message.hpp"
#include "temp_dir.hpp"

using namespace picksight;
using namespace picksight::transport;
using namespace std::chrono_literals;
using picksight::e2e::receiveUntil;
using picksight::test::FakeGvCamera;
using picksight::test::isDiagonalRamp;

namespace {
// The fake camera, and the server with one camera "cam0" on it (free ports),
// a control client and a subscriber to cam0's frames.
struct AravisCell {
  FakeGvCamera fake;
  e2e::VideoServerProcess server{
      {"--source", std::string("cam0=aravis:") + FakeGvCamera::kDeviceId, "--fps", "10"}};
  zmq::context_t context;
  ControlClient client{context, server.control, 10s};
  FrameSubscriber sub{context, server.frames, "cam0", 16};
};

proto::ControlReply call(ControlClient& client, const proto::ControlRequest& request) {
  auto reply = client.call(request);
  INFO(request.ShortDebugString() << " -> " << (reply ? std::string("OK") : reply.error().message));
  REQUIRE(reply);
  return *reply;
}

proto::ControlRequest setFeature(const std::string& name, const std::string& value) {
  proto::ControlRequest r;
  auto* s = r.mutable_set_feature();
  s->set_camera("cam0");
  s->set_name(name);
  s->set_value(value);
  return r;
}

proto::ControlRequest getFeature(const std::string& name) {
  proto::ControlRequest r;
  r.mutable_get_feature()->set_camera("cam0");
  r.mutable_get_feature()->set_name(name);
  return r;
}

proto::ControlRequest describe() {
  proto::ControlRequest r;
  r.mutable_describe_camera()->set_camera("cam0");
  return r;
}

std::string state(ControlClient& client) {
  auto reply = client.call(describe());
  return reply ? reply->describe_camera().summary().state() : "no answer";
}

// Waits for the camera to reach `wanted`; generous, never a timing check.
bool waitForState(ControlClient& client, const std::string& wanted,
                  std::chrono::seconds within = 60s) {
  const auto deadline = std::chrono::steady_clock::now() + within;
  while (std::chrono::steady_clock::now() < deadline) {
    if (state(client) == wanted) return true;
    std::this_thread::sleep_for(100ms);
  }
  return false;
}

}  // namespace

TEST_CASE("video server describes an Aravis camera and sets its features",
          "[aravis][video_server]") {
  AravisCell cell;
  auto& client = cell.client;
  REQUIRE(waitForState(client, "streaming"));

  const auto d = call(client, describe()).describe_camera();
  CHECK(d.vendor() == "Aravis");
  CHECK(d.model() == "Fake");
  CHECK(d.serial() == "GV01");
  CHECK(d.sensor_width() == 2048);
  CHECK(d.sensor_height() == 2048);

  auto exposure = call(client, setFeature("ExposureTimeAbs", "15000")).feature().feature();
  CHECK(exposure.type() == proto::FLOAT);
  CHECK(exposure.value() == "15000");
  auto gain = call(client, setFeature("GainRaw", "2")).feature().feature();
  CHECK(gain.type() == proto::INTEGER);
  CHECK(gain.value() == "2");
  CHECK(call(client, getFeature("GainRaw")).feature().feature().max() == 10);
  auto mode = call(client, getFeature("TriggerMode")).feature().feature();
  CHECK(mode.type() == proto::ENUMERATION);
  CHECK(mode.choices_size() >= 2);

  auto refused = client.call(setFeature("GainRaw", "11"));
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == ControlErrc::kOutOfRange);
  CHECK_THAT(refused.error().message, Catch::Contains("GainRaw") && Catch::Contains("[0, 10]"));
  auto unknown = client.call(getFeature("Gain"));
  REQUIRE_FALSE(unknown);
  CHECK(unknown.error().code == ControlErrc::kUnknownFeature);
  CHECK_THAT(unknown.error().message, Catch::Contains("Gain"));

  proto::ControlRequest list;
  list.mutable_list_features()->set_camera("cam0");
  const auto features = call(client, list).list_features();
  CHECK(features.features_size() > 10);
}

TEST_CASE("video server publishes Aravis frames, cropped and triggered", "[aravis][video_server]") {
  AravisCell cell;
  auto& client = cell.client;
  auto& sub = cell.sub;

  // Free-run: increasing sequence numbers, the camera's own pattern.
  auto first = sub.receive(30s);
  REQUIRE(first);
  uint64_t last = first->info.sequence;
  for (int i = 0; i < 5; ++i) {
    auto f = sub.receive(10s);
    REQUIRE(f);
    CHECK(f->info.sequence > last);
    last = f->info.sequence;
    CHECK(f->info.width == 512);
    CHECK(f->image.type() == CV_8UC1);
    CHECK(f->info.device_timestamp_ns > 0);
    CHECK(isDiagonalRamp(f->image));
  }

  SECTION("the camera's ROI through features and the server's own ROI") {
    call(client, setFeature("Width", "320"));
    call(client, setFeature("Height", "240"));
    auto narrow = receiveUntil(
        sub, [](const Frame& f) { return f.info.width == 320 && f.info.height == 240; });
    REQUIRE(narrow);
    CHECK(narrow->info.height == 240);
    CHECK(isDiagonalRamp(narrow->image));

    proto::ControlRequest roi;
    roi.mutable_set_roi()->set_camera("cam0");
    roi.mutable_set_roi()->mutable_roi()->set_x(100);
    roi.mutable_set_roi()->mutable_roi()->set_y(50);
    roi.mutable_set_roi()->mutable_roi()->set_width(120);
    roi.mutable_set_roi()->mutable_roi()->set_height(80);
    call(client, roi);
    auto cropped = receiveUntil(sub, [](const Frame& f) { return f.info.width == 120; });
    REQUIRE(cropped);
    CHECK(cropped->info.height == 80);
    CHECK(cropped->mapping.roi_x == 100);
    CHECK(cropped->mapping.roi_y == 50);
    CHECK(isDiagonalRamp(cropped->image));
  }

  SECTION("software trigger: one frame per trigger, with the sequence the reply named") {
    proto::ControlRequest mode;
    mode.mutable_set_mode()->set_camera("cam0");
    mode.mutable_set_mode()->set_mode(proto::TRIGGER);
    call(client, mode);
    REQUIRE(waitForState(client, "streaming"));
    // Drain what free-run sent before the switch.
    while (sub.receive(1500ms)) {
    }
    proto::ControlRequest trigger;
    trigger.mutable_trigger()->set_camera("cam0");
    for (int i = 0; i < 3; ++i) {
      const auto ticket = call(client, trigger).trigger();
      CHECK(ticket.triggered());
      auto f = sub.receive(10s);
      REQUIRE(f);
      CHECK(f->info.sequence == ticket.sequence());
      CHECK(f->info.triggered);
      CHECK(isDiagonalRamp(f->image));
      // Exactly one: nothing more until the next trigger.
      CHECK_FALSE(sub.receive(1s));
    }
  }

  SECTION("Bayer frames are standardized to the output format") {
    call(client, setFeature("PixelFormat", "BayerRG8"));
    proto::ControlRequest format;
    format.mutable_set_format()->set_camera("cam0");
    format.mutable_set_format()->set_pixel_format(proto::BGR8);
    call(client, format);
    auto colour = receiveUntil(sub, [](const Frame& f) { return f.image.type() == CV_8UC3; });
    REQUIRE(colour);
    CHECK(colour->info.width == 512);
    CHECK(colour->image.type() == CV_8UC3);
    // Demosaiced from a colour mosaic: the channels differ somewhere.
    std::vector<cv::Mat> channels;
    cv::split(colour->image, channels);
    CHECK(cv::norm(channels[0], channels[2], cv::NORM_INF) > 0);
  }
}

TEST_CASE("a killed Aravis camera is reconnected and resumes on the same topic",
          "[aravis][video_server]") {
  AravisCell cell;
  auto& client = cell.client;
  auto& sub = cell.sub;
  auto before = sub.receive(30s);
  REQUIRE(before);

  cell.fake.kill();
  REQUIRE(waitForState(client, "reconnecting"));
  while (sub.receive(500ms)) {
  }

  cell.fake.start();
  REQUIRE(waitForState(client, "streaming"));
  // The same subscriber, never reconnected, gets frames again.
  auto after = sub.receive(30s);
  REQUIRE(after);
  CHECK(after->info.sequence > before->info.sequence);
  CHECK(isDiagonalRamp(after->image));

  proto::ControlRequest stats;
  stats.mutable_statistics()->set_camera("cam0");
  const auto reply = call(client, stats).statistics();
  REQUIRE(reply.cameras_size() == 1);
  CHECK(reply.cameras(0).reconnects() >= 1);
}

TEST_CASE("configured frame rate and hardware trigger of an Aravis camera survive its opening",
          "[aravis][video_server]") {
  FakeGvCamera fake;
  picksight::test::TempDir dir;
  // No `fps:` and no `mode:`: the camera's own settings, from features.
  const std::string config = dir.write("server.yaml", std::string(R"(
cameras:
  - name: cam0
    source: "aravis:)") + FakeGvCamera::kDeviceId + R"("
    # Triggered by a line nothing drives: no frames, and none expected yet.
    no_frame_timeout: 600
    features:
      AcquisitionFrameRate: 7.5
      TriggerMode: "On"
      TriggerSource: Line0
)");
  e2e::VideoServerProcess server{{"--config", config}};
  zmq::context_t context;
  ControlClient client{context, server.control, 10s};
  REQUIRE(waitForState(client, "streaming"));
  const auto rate = call(client, getFeature("AcquisitionFrameRate")).feature().feature();
  CHECK(std::stod(rate.value()) == Approx(7.5));
  CHECK(call(client, getFeature("TriggerMode")).feature().feature().value() == "On");
  CHECK(call(client, getFeature("TriggerSource")).feature().feature().value() == "Line0");
}
