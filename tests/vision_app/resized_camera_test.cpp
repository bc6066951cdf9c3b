// Models are in sensor pixels: a part learned at full size (LEARN AT on a
// scene of several) is still found at the same sensor positions once the
// camera is resized or cropped through the video server's control socket.
// Real video server and vision app, real sockets.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "cell_fixture.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::transport;
using namespace picksight::tool_support;
using namespace std::chrono_literals;

namespace {
// The largest distance from a synthetic part's centre to its outline
// (size=150: the longest side), with the blur around it.
constexpr double kReach = 0.75 * 150 + 4;

std::string ask(LineClient& robot, const std::string& line) {
  auto reply = robot.request(line, 10s);
  REQUIRE(reply);
  return *reply;
}

void camera(const VideoServerProcess& server, std::vector<std::string> args) {
  args.insert(args.begin(), {binPath("picksight-cam"), "--control", server.control});
  const auto result = run(args);
  INFO(result.out);
  REQUIRE(result.exit_code == 0);
}

// Every truth part whose whole outline lies inside `roi` (sensor pixels) is
// in the reply within `tolerance`, and every pose of the reply is a part.
void checkFound(const std::string& reply, const std::vector<TruthPart>& truth,
                const cv::Rect2d& roi, double tolerance) {
  INFO("reply: " << reply);
  const auto poses = imagePoses(reply);
  const auto distance = [](const Pose& p, const TruthPart& t) {
    return std::hypot(p.x - t.x, p.y - t.y);
  };
  size_t inside = 0;
  for (const auto& t : truth) {
    const cv::Rect2d extent(t.x - kReach, t.y - kReach, 2 * kReach, 2 * kReach);
    if ((extent & roi).area() < extent.area()) continue;
    ++inside;
    double best = std::numeric_limits<double>::max();
    for (const auto& p : poses) best = std::min(best, distance(p, t));
    INFO("part at " << t.x << ", " << t.y);
    CHECK(best < tolerance);
  }
  CHECK(inside > 0);
  for (const auto& p : poses) {
    double best = std::numeric_limits<double>::max();
    for (const auto& t : truth) best = std::min(best, distance(p, t));
    INFO("pose at " << p.x << ", " << p.y);
    CHECK(best < tolerance);
  }
}

}  // namespace

TEST_CASE("a part learned at full size is found after the camera is resized or cropped",
          "[e2e][learn][resized]") {
  // One fixed layout of six L shapes, a new frame for every trigger.
  VideoServerProcess server({"--source",
                             "cam0=synthetic:width=1280,height=960,parts=6,types=l_shape,seed=5,"
                             "size=150",
                             "--mode", "trigger"});
  VisionProcess vision(server);
  zmq::context_t context;
  FrameSubscriber watcher(context, server.frames, "cam0", 16);
  waitForSubscription(server, watcher);
  camera(server, {"trigger", "cam0"});
  auto frame = receiveUntil(watcher, [](const Frame& f) { return !f.truth.empty(); });
  REQUIRE(frame);
  const std::vector<TruthPart> truth = frame->truth;
  REQUIRE(truth.size() == 6);
  auto robot = vision.connect();

  // LEARN AT around the part farthest from the others.
  const TruthPart* alone = nullptr;
  double room = 0;
  for (const auto& t : truth) {
    double nearest = std::numeric_limits<double>::max();
    for (const auto& o : truth) {
      if (&o != &t) nearest = std::min(nearest, std::hypot(o.x - t.x, o.y - t.y));
    }
    if (nearest > room) {
      room = nearest;
      alone = &t;
    }
  }
  REQUIRE(alone);
  const int x = static_cast<int>(alone->x - kReach);
  const int y = static_cast<int>(alone->y - kReach);
  const int side = static_cast<int>(2 * kReach);
  const std::string learn = "LEARN 1 bracket AT " + std::to_string(x) + " " + std::to_string(y) +
                            " " + std::to_string(side) + " " + std::to_string(side);
  const std::string learned = ask(robot, learn);
  INFO(learn << " -> " << learned);
  REQUIRE(learned.rfind("OK 1 bracket ", 0) == 0);
  CHECK(learned.find(';') == std::string::npos);

  const cv::Rect2d sensor(0, 0, 1280, 960);
  checkFound(ask(robot, "LOCATE 1"), truth, sensor, 0.1);

  // Half the pixels each way: positions to a few tenths of a sensor pixel,
  // on every LOCATE (the scaled models are kept from one to the next).
  camera(server, {"size", "cam0", "--scale", "0.5"});
  for (int i = 0; i < 3; ++i) checkFound(ask(robot, "LOCATE 1"), truth, sensor, 0.3);
  // A LEARN while resized and a FORGET change the models: every type still
  // finds every part.
  const std::string second = "LEARN 2 again AT " + std::to_string(x) + " " + std::to_string(y) +
                             " " + std::to_string(side) + " " + std::to_string(side);
  const std::string relearned = ask(robot, second);
  INFO(second << " -> " << relearned);
  REQUIRE(relearned.rfind("OK 2 again ", 0) == 0);
  checkFound(ask(robot, "LOCATE 2"), truth, sensor, 0.3);
  checkFound(ask(robot, "LOCATE 1"), truth, sensor, 0.3);
  REQUIRE(ask(robot, "FORGET 2").rfind("OK", 0) == 0);
  checkFound(ask(robot, "LOCATE 1"), truth, sensor, 0.3);

  // Back to full size, then cropped to the left half of the sensor.
  camera(server, {"size", "cam0", "0", "0"});
  camera(server, {"roi", "cam0", "0", "0", "640", "960"});
  checkFound(ask(robot, "LOCATE 1"), truth, cv::Rect2d(0, 0, 640, 960), 0.1);
  // And the right half, resized as well.
  camera(server, {"roi", "cam0", "640", "0", "640", "960"});
  camera(server, {"size", "cam0", "--scale", "0.5"});
  checkFound(ask(robot, "LOCATE 1"), truth, cv::Rect2d(640, 0, 640, 960), 0.3);
}
