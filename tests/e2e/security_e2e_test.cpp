// The robot port's protections with the real processes: a read-only robot
// port beside a full set-up port, an allow-list that turns peers away, and
// a camera whose image file goes away answering LOCATE with an error
// instead of old positions.
#include <catch2/catch.hpp>

#include "picksight/codecs/codecs.hpp"

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>

#include "cell_fixture.hpp"
#include "temp_dir.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::tool_support;
using namespace std::chrono_literals;

namespace {
const std::vector<std::string> kSynthetic = {
    "--source", "cam0=synthetic:width=320,height=240,parts=2,size=40", "--mode", "trigger"};

// Polls `line` until the reply starts with `prefix`; the last reply.
std::string requestUntil(LineClient& robot, const std::string& line, const std::string& prefix) {
  std::string reply;
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (std::chrono::steady_clock::now() < deadline) {
    auto r = robot.request(line, 10s);
    REQUIRE(r);
    reply = *r;
    if (reply.rfind(prefix, 0) == 0) break;
    std::this_thread::sleep_for(50ms);
  }
  return reply;
}
}  // namespace

TEST_CASE("a read-only robot port refuses changes that the set-up port makes", "[e2e][security]") {
  VideoServerProcess server(kSynthetic);
  VisionProcess vision(server, "cam0", "", {"--robot-read-only", "--setup-port", "0"});
  REQUIRE(vision.setup_port != 0);
  auto robot = vision.connect();
  auto setup = LineClient::connect("127.0.0.1", vision.setup_port, 5s);
  REQUIRE(setup);

  CHECK(robot.request("STATUS", 10s)->rfind("OK ", 0) == 0);
  CHECK(robot.request("LOCATE 1", 10s)->rfind("OK ", 0) == 0);
  CHECK(*robot.request("ROI", 10s) == "OK 0 0 320 240");
  for (const char* change : {"LEARN 1", "ROI 0 0 8 8", "EXPOSURE 100", "STORE 1 2", "COMPUTE",
                             "FORGET 1", "GRASP 1 CLEAR"}) {
    INFO(change);
    CHECK(robot.request(change, 10s)->rfind("ERROR 17 ", 0) == 0);
  }
  CHECK(*robot.request("ROI", 10s) == "OK 0 0 320 240");

  CHECK(*setup->request("ROI 0 0 160 120", 10s) == "OK");
  CHECK(*robot.request("ROI", 10s) == "OK 0 0 160 120");
  CHECK(*setup->request("ROI FULL", 10s) == "OK");
}

TEST_CASE("a peer outside --robot-allow is told so and closed", "[e2e][security]") {
  VideoServerProcess server(kSynthetic);
  VisionProcess vision(server, "cam0", "", {"--robot-allow", "192.0.2.0/24"});
  for (int i = 0; i < 2; ++i) {
    auto robot = vision.connect();
    auto reply = robot.readLine(5s);
    REQUIRE(reply);
    CHECK(reply->rfind("ERROR 15 address 127.0.0.1 is not allowed", 0) == 0);
    CHECK_FALSE(robot.readLine(2s));
  }
  VisionProcess allowed(server, "cam0", "", {"--robot-allow", "192.0.2.0/24, 127.0.0.1"});
  auto robot = allowed.connect();
  CHECK(*robot.request("PING", 5s) == "OK");
}

TEST_CASE("LOCATE on a file camera whose file is gone is an error until it returns",
          "[e2e][security]") {
  test::TempDir dir;
  const std::string path = (dir.path() / "scene.png").string();
  REQUIRE(picksight::codecs::imwrite(path, cv::Mat(240, 320, CV_8UC1, cv::Scalar(255))));
  VideoServerProcess server({"--source", "cam0=file:" + path, "--mode", "trigger"});
  VisionProcess vision(server);
  auto robot = vision.connect();
  CHECK(requestUntil(robot, "LOCATE 1", "OK ").rfind("OK ", 0) == 0);

  std::filesystem::remove(path);
  const std::string failing = requestUntil(robot, "LOCATE 1", "ERROR 22 ");
  CHECK(failing.rfind("ERROR 22 ", 0) == 0);
  CHECK_THAT(failing, Catch::Contains("not streaming") && Catch::Contains(path));
  // Every LOCATE now says so, at once: none waits for a frame.
  CHECK(robot.request("LOCATE 1", 10s)->rfind("ERROR 22 ", 0) == 0);

  REQUIRE(picksight::codecs::imwrite(path, cv::Mat(240, 320, CV_8UC1, cv::Scalar(255))));
  CHECK(requestUntil(robot, "LOCATE 1", "OK ").rfind("OK ", 0) == 0);
}
