// LOCATE end to end: synthetic camera -> video server -> ZeroMQ -> vision
// app -> TCP robot client, against the scene's ground truth.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "cell_fixture.hpp"
#include "picksight/common/angles.hpp"
#include "picksight/common/clock.hpp"
#include "picksight/common/text.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::transport;
using namespace picksight::tool_support;
using namespace std::chrono_literals;

namespace {
// "OK cam seq host_ns width height triggered" from FRAME.
struct UsedFrame {
  uint64_t sequence = 0;
  uint64_t host_ns = 0;
  bool triggered = false;
};

UsedFrame usedFrame(LineClient& robot) {
  auto reply = robot.request("FRAME", 5s);
  REQUIRE(reply);
  const auto w = splitFields(*reply, " ");
  REQUIRE(w.size() == 7);
  REQUIRE(w[0] == "OK");
  UsedFrame f;
  f.sequence = static_cast<uint64_t>(parseInt(w[2]).value_or(0));
  f.host_ns = static_cast<uint64_t>(parseInt(w[3]).value_or(0));
  f.triggered = w[6] == "1";
  return f;
}
}  // namespace

TEST_CASE("LOCATE matches the synthetic ground truth", "[e2e][locate]") {
  // A new layout on every trigger, so each request sees a different scene.
  VideoServerProcess server({"--source",
                             "cam0=synthetic:width=1280,height=960,parts=8,seed=11,scene_every=1",
                             "--mode", "trigger"});
  VisionProcess vision(server);
  zmq::context_t context;
  FrameSubscriber watcher(context, server.frames, "cam0", 16);
  waitForSubscription(server, watcher);  // the LOCATE frames must all reach it
  auto robot = vision.connect();

  double worst_position = 0;
  double worst_angle = 0;
  int parts_checked = 0;
  for (int request = 0; request < 4; ++request) {
    auto reply = robot.request("LOCATE 1", 10s);
    REQUIRE(reply);
    INFO("reply: " << *reply);
    const auto poses = imagePoses(*reply);
    const UsedFrame used = usedFrame(robot);
    auto frame =
        receiveUntil(watcher, [&](const Frame& f) { return f.info.sequence == used.sequence; });
    REQUIRE(frame);
    const auto& truth = frame->truth;
    REQUIRE(truth.size() == 8);
    CHECK(poses.size() == static_cast<size_t>(truth.size()));
    for (const auto& t : truth) {
      double best = std::numeric_limits<double>::max();
      const Pose* match = nullptr;
      for (const auto& p : poses) {
        const double d = std::hypot(p.x - t.x, p.y - t.y);
        if (d < best) {
          best = d;
          match = &p;
        }
      }
      REQUIRE(match);
      INFO(t.type << " at " << t.x << ", " << t.y << " angle " << t.angle_deg);
      // Replies carry 3 decimals: 0.0005 of rounding on top of the error.
      CHECK(best < 0.1);
      const double angle_error = angleDiffDeg(match->rz, t.angle_deg, t.symmetry_deg);
      CHECK(angle_error < 0.5);
      worst_position = std::max(worst_position, best);
      worst_angle = std::max(worst_angle, angle_error);
      ++parts_checked;
    }
  }
  WARN("worst position error " << worst_position << " px, worst angle error " << worst_angle
                               << " deg over " << parts_checked << " parts");
}

TEST_CASE("a malformed robot line gets ERROR and the connection goes on", "[e2e][locate]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=3", "--mode", "trigger"});
  VisionProcess vision(server);
  auto robot = vision.connect();
  // Each fault has its own code: bad arguments 11, unknown command 10 (binary
  // bytes are an unknown command too), empty line 14.
  const std::vector<std::pair<std::string, std::string>> bad_lines = {
      {"LOCATE", "ERROR 11 "},
      {"LOCATE x", "ERROR 11 "},
      {"FLY 1 2", "ERROR 10 "},
      {std::string("\x01\x02\xff", 3), "ERROR 10 "},
      {"", "ERROR 14 "}};
  for (const auto& [bad, expected] : bad_lines) {
    auto reply = robot.request(bad, 5s);
    REQUIRE(reply);
    INFO("request '" << bad << "' got '" << *reply << "'");
    CHECK(reply->rfind(expected, 0) == 0);
  }
  auto reply = robot.request("locate,1", 10s);
  REQUIRE(reply);
  CHECK(parseLocateReply(*reply).size() == 3);
  CHECK(*robot.request("PING", 5s) == "OK");
}

TEST_CASE("the frame used after a trigger was produced after the request", "[e2e][locate]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=2", "--mode", "trigger"});
  VisionProcess vision(server);
  auto robot = vision.connect();
  uint64_t last_sequence = 0;
  for (int i = 0; i < 3; ++i) {
    const uint64_t before = realtimeNs();
    auto reply = robot.request("LOCATE 1", 10s);
    REQUIRE(reply);
    REQUIRE(reply->rfind("OK ", 0) == 0);
    const UsedFrame used = usedFrame(robot);
    CHECK(used.triggered);
    CHECK(used.host_ns > before);
    CHECK(used.sequence > last_sequence);
    last_sequence = used.sequence;
  }
}

TEST_CASE("in free-run LOCATE waits for a frame taken after the request", "[e2e][locate]") {
  // A slow camera: the newest frame is usually older than the request.
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=2", "--fps", "4"});
  VisionProcess vision(server);
  auto robot = vision.connect();
  for (int i = 0; i < 3; ++i) {
    const uint64_t before = realtimeNs();
    auto reply = robot.request("LOCATE 1", 10s);
    REQUIRE(reply);
    REQUIRE(reply->rfind("OK ", 0) == 0);
    const UsedFrame used = usedFrame(robot);
    CHECK_FALSE(used.triggered);
    CHECK(used.host_ns > before);
  }
}

TEST_CASE("LEARN a part, then LOCATE finds it turned from the trained pose",
          "[e2e][locate][models]") {
  // One L per frame, in a new pose on every trigger.
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=1,types=l_shape,seed=3,scene_every=1",
       "--mode", "trigger"});
  VisionProcess vision(server);
  zmq::context_t context;
  FrameSubscriber watcher(context, server.frames, "cam0", 16);
  waitForSubscription(server, watcher);
  auto robot = vision.connect();
  const auto truthOf = [&](uint64_t sequence) {
    auto frame = receiveUntil(watcher, [&](const Frame& f) { return f.info.sequence == sequence; });
    REQUIRE(frame);
    REQUIRE(frame->truth.size() == 1);
    return frame->truth[0];
  };

  CHECK(*robot.request("MODELS", 5s) == "OK 0");
  auto reply = robot.request("LEARN 1 bracket", 10s);
  REQUIRE(reply);
  INFO("LEARN reply: " << *reply);
  REQUIRE(reply->rfind("OK 1 bracket ", 0) == 0);
  const auto trained = truthOf(usedFrame(robot).sequence);
  reply = robot.request("MODELS", 5s);
  REQUIRE(reply);
  CHECK(reply->rfind("OK 1 1 bracket ", 0) == 0);

  for (int i = 0; i < 3; ++i) {
    reply = robot.request("LOCATE 1", 10s);
    REQUIRE(reply);
    INFO("LOCATE reply: " << *reply);
    const auto poses = imagePoses(*reply);
    const auto truth = truthOf(usedFrame(robot).sequence);
    REQUIRE(poses.size() == 1);
    CHECK(std::hypot(poses[0].x - truth.x, poses[0].y - truth.y) < 0.1);
    CHECK(angleDiffDeg(poses[0].rz, truth.angle_deg - trained.angle_deg) < 0.3);
  }
  // Another type is not trained: refused, no frame taken.
  reply = robot.request("LOCATE 2", 5s);
  REQUIRE(reply);
  CHECK(reply->rfind("ERROR 32 ", 0) == 0);

  reply = robot.request("BLOBS", 10s);
  REQUIRE(reply);
  const auto fields = splitFields(*reply, " ");
  REQUIRE(fields.size() == 2 + 19);
  CHECK(fields[1] == "1");

  CHECK(*robot.request("FORGET 1", 5s) == "OK");
  CHECK(*robot.request("MODELS", 5s) == "OK 0");
  reply = robot.request("LOCATE 1", 10s);
  REQUIRE(reply);
  CHECK(parseLocateReply(*reply).size() == 1);  // no models: every region again
}

TEST_CASE("LEARN refuses a frame with no part or several", "[e2e][locate][models]") {
  VideoServerProcess several(
      {"--source", "cam0=synthetic:width=640,height=480,parts=3", "--mode", "trigger"});
  VisionProcess vision(several);
  auto robot = vision.connect();
  auto reply = robot.request("LEARN 4", 10s);
  REQUIRE(reply);
  CHECK(reply->rfind("ERROR 31 ", 0) == 0);
  VideoServerProcess none(
      {"--source", "cam0=synthetic:width=640,height=480,parts=0", "--mode", "trigger"});
  VisionProcess vision_none(none);
  auto robot_none = vision_none.connect();
  reply = robot_none.request("LEARN 4", 10s);
  REQUIRE(reply);
  CHECK(reply->rfind("ERROR 30 ", 0) == 0);
  CHECK(*robot_none.request("MODELS", 5s) == "OK 0");
}

TEST_CASE("LEARNVIEW reads a taught part again where it lies and moves the origin by the median",
          "[e2e][locate][models]") {
  // One L per frame, in a new pose on every trigger: each view lies elsewhere.
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=1,types=l_shape,seed=5,scene_every=1",
       "--mode", "trigger"});
  VisionProcess vision(server);
  auto robot = vision.connect();

  auto reply = robot.request("LEARNVIEW 1", 10s);
  REQUIRE(reply);
  CHECK(reply->rfind("ERROR 32 ", 0) == 0);  // nothing taught yet
  REQUIRE(robot.request("LEARN 1 bracket", 10s)->rfind("OK 1 bracket ", 0) == 0);
  double shift = 0;
  for (int views = 2; views <= 4; ++views) {
    reply = robot.request("LEARNVIEW 1", 10s);
    REQUIRE(reply);
    INFO("LEARNVIEW reply: " << *reply);
    const std::string head = reply->substr(0, reply->find(" ; "));
    const auto fields = splitFields(head, " ");
    REQUIRE(fields.size() == 7);
    CHECK(fields[0] == "OK");
    CHECK(fields[1] == "1");
    CHECK(fields[2] == "bracket");
    CHECK(fields[3] == std::to_string(views));
    shift = std::hypot(std::stod(std::string(fields[4])), std::stod(std::string(fields[5])));
    CHECK(shift <= 1.0);
    CHECK(std::stod(std::string(fields[6])) >= 0);
    CHECK(reply->find(" ; note: this view read the centroid at ") != std::string::npos);
  }
  // The model still finds the part where it is (the synthetic truth is its
  // centroid).
  zmq::context_t context;
  FrameSubscriber watcher(context, server.frames, "cam0", 16);
  waitForSubscription(server, watcher);
  reply = robot.request("LOCATE 1", 10s);
  REQUIRE(reply);
  const auto poses = imagePoses(*reply);
  const auto sequence = usedFrame(robot).sequence;
  auto frame = receiveUntil(watcher, [&](const Frame& f) { return f.info.sequence == sequence; });
  REQUIRE(frame);
  REQUIRE(frame->truth.size() == 1);
  REQUIRE(poses.size() == 1);
  CHECK(std::hypot(poses[0].x - frame->truth[0].x, poses[0].y - frame->truth[0].y) < 0.1);

  // UNDO takes back one view: the next LEARNVIEW counts 4 again.
  reply = robot.request("UNDO", 5s);
  REQUIRE(reply);
  CHECK(reply->rfind("OK 1 restored ", 0) == 0);
  reply = robot.request("LEARNVIEW 1", 10s);
  REQUIRE(reply);
  CHECK(reply->rfind("OK 1 bracket 4 ", 0) == 0);

  // Bad requests change nothing.
  for (const char* line : {"LEARNVIEW", "LEARNVIEW x", "LEARNVIEW 1 AT 1 2 3",
                           "LEARNVIEW 1 IN 0 0 9 9", "LEARNVIEW 1 AT 0 0 0 9"}) {
    reply = robot.request(line, 5s);
    REQUIRE(reply);
    INFO(line << " -> " << *reply);
    CHECK(reply->rfind("ERROR 11 ", 0) == 0);
  }
  reply = robot.request("LEARNVIEW 1 AT 0 0 4 4", 10s);  // a corner of the frame, no part there
  REQUIRE(reply);
  CHECK(reply->rfind("ERROR 35 ", 0) == 0);
  reply = robot.request("LEARNVIEW 1", 10s);
  REQUIRE(reply);
  CHECK(reply->rfind("OK 1 bracket 5 ", 0) == 0);

  // A part that looks alike turned has its origin at its centre of symmetry.
  VideoServerProcess bars(
      {"--source",
       "cam0=synthetic:width=640,height=480,parts=1,types=rectangle,seed=5,scene_every=1", "--mode",
       "trigger"});
  VisionProcess bar_cell(bars);
  auto bar_robot = bar_cell.connect();
  REQUIRE(bar_robot.request("LEARN 2 bar", 10s)->rfind("OK 2 bar ", 0) == 0);
  reply = bar_robot.request("LEARNVIEW 2", 10s);
  REQUIRE(reply);
  INFO("LEARNVIEW of a bar: " << *reply);
  CHECK(reply->rfind("ERROR 39 ", 0) == 0);
  CHECK(reply->find("symmetry") != std::string::npos);
}
