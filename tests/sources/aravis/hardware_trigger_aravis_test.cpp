// A robot's LOCATE on a hardware-triggered camera, through the whole chain:
// robot -> picksight-vision -> picksight-video-server -> Aravis -> Aravis's
// fake GigE camera. The fake camera has no wired input, so its trigger source
// "Software" stands in for the line: the test fires its TriggerSoftware
// command over the video server's control socket, as the robot's digital
// output would pulse Line1. The vision app itself must never trigger it.
#include <catch2/catch.hpp>

#include <sstream>

#include <zmq.hpp>

#include "cell_fixture.hpp"
#include "fake_gv_camera.hpp"
#include "picksight/transport/control_client.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::transport;
using namespace picksight::tool_support;
using namespace std::chrono_literals;

namespace {

std::string mustRequest(LineClient& robot, const std::string& line) {
  auto reply = robot.request(line, 30s);
  INFO(line);
  REQUIRE(reply);
  return *reply;
}

uint64_t lastSequence(ControlClient& control) {
  proto::ControlRequest stats;
  stats.mutable_statistics()->set_camera("cam0");
  auto reply = control.call(stats);
  REQUIRE(reply);
  REQUIRE(reply->statistics().cameras_size() == 1);
  return reply->statistics().cameras(0).last_sequence();
}

// The stand-in for the robot's pulse on the line.
void pulse(ControlClient& control) {
  proto::ControlRequest r;
  auto* set = r.mutable_set_feature();
  set->set_camera("cam0");
  set->set_name("TriggerSoftware");
  auto reply = control.call(r);
  INFO((reply ? std::string("OK") : reply.error().message));
  REQUIRE(reply);
}

}  // namespace

TEST_CASE("LOCATE on a hardware-triggered camera waits for the pulse and times out with ERROR 23",
          "[aravis][cell][camera]") {
  test::FakeGvCamera fake;
  VideoServerProcess server(
      {"--source", std::string("cam0=aravis:") + test::FakeGvCamera::kDeviceId, "--fps", "10"});
  VisionProcess vision(server);
  zmq::context_t context;
  ControlClient control{context, server.control, 10s};
  auto robot = vision.connect();

  CHECK(mustRequest(robot, "CAMMODE") == "OK FREE 10.000");
  CHECK(mustRequest(robot, "CAMMODE HARDWARE Software 1500") == "OK HARDWARE Software 1500");
  CHECK(mustRequest(robot, "cammode") == "OK HARDWARE Software 1500");

  // Nobody pulses: no frame, whatever the vision app does on its side (a
  // software trigger would make one, the source being "Software").
  const std::string timed_out = mustRequest(robot, "LOCATE 1");
  CHECK_THAT(timed_out, Catch::StartsWith("ERROR 23 ") && Catch::Contains("Software") &&
                            Catch::Contains("1500 ms"));

  // Pulses while the LOCATE waits; the ones that come before the request
  // reached the vision app must not serve it. No timing is asserted: the
  // pulses go on until the reply comes or the deadline passes.
  const uint64_t before = lastSequence(control);
  REQUIRE(robot.sendRaw("LOCATE 1\n"));
  std::optional<std::string> reply;
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (!reply && std::chrono::steady_clock::now() < deadline) {
    pulse(control);
    if (auto line = robot.readLine(300ms)) reply = *line;
  }
  REQUIRE(reply);
  CHECK_THAT(*reply, Catch::StartsWith("OK "));
  // "OK <camera> <sequence> ...": the frame it worked on came after the request.
  std::istringstream frame(mustRequest(robot, "FRAME"));
  std::string ok, camera;
  uint64_t sequence = 0;
  frame >> ok >> camera >> sequence;
  CHECK(ok == "OK");
  CHECK(sequence > before);

  // Back to free-run: frames without pulses.
  CHECK(mustRequest(robot, "CAMMODE FREE 20") == "OK FREE 20.000");
  CHECK_THAT(mustRequest(robot, "LOCATE 1"), Catch::StartsWith("OK "));
}

TEST_CASE("CAMMODE names what is wrong and a camera without a trigger input refuses HARDWARE",
          "[cell][camera]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240,parts=1"});
  VisionProcess vision(server);
  auto robot = vision.connect();
  CHECK_THAT(mustRequest(robot, "CAMMODE HARDWARE Line1"),
             Catch::StartsWith("ERROR 22 ") && Catch::Contains("hardware trigger"));
  CHECK_THAT(mustRequest(robot, "CAMMODE SOFTWARE"), Catch::Equals("OK SOFTWARE"));
  CHECK_THAT(mustRequest(robot, "LOCATE 1"), Catch::StartsWith("OK "));
  CHECK_THAT(mustRequest(robot, "CAMMODE FREE 0"), Catch::StartsWith("ERROR 11 "));
  CHECK_THAT(mustRequest(robot, "CAMMODE HARDWARE Line/1"), Catch::StartsWith("ERROR 11 "));
  CHECK_THAT(mustRequest(robot, "CAMMODE HARDWARE Line1 0"), Catch::StartsWith("ERROR 11 "));
  CHECK_THAT(mustRequest(robot, "CAMMODE SLOW"), Catch::StartsWith("ERROR 11 usage"));
  CHECK(mustRequest(robot, "CAMMODE") == "OK SOFTWARE");
}
