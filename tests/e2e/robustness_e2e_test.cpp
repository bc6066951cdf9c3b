// Robot clients at their worst against a real vision app: 32 connections
// at once, garbage, binary bytes, empty and 1 MB lines, clients that vanish
// mid-request. The server must answer every well-formed request, stay up,
// and leave stored data (calibration, models) unchanged byte for byte.
#include <catch2/catch.hpp>

#include <atomic>
#include <cmath>
#include <mutex>
#include <random>
#include <thread>

#include "cell_fixture.hpp"
#include "picksight/common/angles.hpp"
#include "picksight/common/atomic_file.hpp"
#include "picksight/common/text.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::tool_support;
using namespace std::chrono_literals;

namespace {
// Failures seen by client threads (Catch2 assertions are for the main thread).
struct Failures {
  std::mutex mutex;
  std::vector<std::string> messages;
  void add(const std::string& m) {
    std::lock_guard<std::mutex> lock(mutex);
    if (messages.size() < 20) messages.push_back(m);
  }
};

// The single part of a LOCATE reply "OK 1 x y rz" where it lies within half a
// pixel of `expected` (the scene never moves; only its noise changes), else
// why not. Client threads cannot use Catch2's REQUIREs, so no
// parseLocateReply here.
std::string locateMismatch(const std::string& reply, const Pose& expected) {
  const auto w = splitFields(reply, " ");
  if (w.size() != 5 || w[0] != "OK" || w[1] != "1") return "not one part: " + reply;
  const auto x = parseDouble(w[2]);
  const auto y = parseDouble(w[3]);
  const auto rz = parseDouble(w[4]);
  if (!x || !y || !rz) return "not numbers: " + reply;
  // A rectangle: its angle is defined modulo 180 degrees.
  if (std::abs(*x - expected.x) > 0.5 || std::abs(*y - expected.y) > 0.5 ||
      angleDiffDeg(*rz, expected.rz, 180) > 1.0)
    return "moved: " + reply;
  return "";
}

std::string garbage(std::mt19937& rng, size_t size) {
  std::string s(size, '\0');
  for (auto& c : s) c = static_cast<char>(rng() & 0xff);
  for (auto& c : s) {
    if (c == '\n') c = 'x';  // lines are counted by the caller
  }
  return s;
}
}  // namespace

TEST_CASE("32 robots at once, garbage and vanishing clients change nothing stored",
          "[e2e][robustness]") {
  VideoServerProcess server({"--source",
                             "cam0=synthetic:width=640,height=480,parts=1,types=rectangle,seed=4",
                             "--mode", "trigger"});
  // 32 robots from one address, and the setup connection, which the server
  // may not have seen closed yet when the last robot connects: room for all
  // (the per-address limit of 32 is tested on its own).
  VisionProcess vision(server, "cam0", "", {"--robot-per-address", "40"});
  // Where the one part lies when a single robot asks: every LOCATE under load
  // must find it there, not merely answer OK.
  Pose located_alone{};
  {
    auto setup = vision.connect();
    auto r = setup.request("LEARN 1 bar", 10s);
    REQUIRE(r);
    REQUIRE(r->rfind("OK ", 0) == 0);
    REQUIRE(*setup.request("GRASP 1 ADD 0 0 90", 5s) == "OK 1");
    REQUIRE(*setup.request("GRIPPER 1 FINGER -40 0 5 10", 5s) == "OK 1");
    REQUIRE(*setup.request("STORE 10 20", 10s) == "OK 1");
    r = setup.request("LOCATE 1", 10s);
    REQUIRE(r);
    const auto poses = parseLocateReply(*r);
    REQUIRE(poses.size() == 1);
    located_alone = poses[0];
  }
  const std::string calibration_path = vision.data_dir + "/calibration.yaml";
  const std::string model_path = vision.data_dir + "/models/type_1.yaml";
  const auto calibration_before = readFile(calibration_path);
  const auto model_before = readFile(model_path);
  REQUIRE(calibration_before);
  REQUIRE(model_before);

  Failures failures;
  std::atomic<int> replies{0};
  std::vector<std::thread> robots;
  for (int id = 0; id < 32; ++id) {
    robots.emplace_back([&, id] {
      std::mt19937 rng(static_cast<unsigned>(id) + 1);
      auto connected = LineClient::connect("127.0.0.1", vision.robot_port, 5s);
      if (!connected) return failures.add("robot " + std::to_string(id) + ": cannot connect");
      LineClient robot = std::move(*connected);
      const auto expect = [&](const std::string& what, bool ok) {
        if (!ok) failures.add("robot " + std::to_string(id) + ": " + what);
      };
      for (int i = 0; i < 12; ++i) {
        switch ((id + i) % 4) {
          case 0: {
            auto r = robot.request("PING", 10s);
            expect("PING", r && *r == "OK");
            break;
          }
          case 1: {
            auto r = robot.request("LOCATE 1", 20s);
            const std::string wrong = r ? locateMismatch(*r, located_alone) : r.error().message;
            expect("LOCATE 1: " + wrong, wrong.empty());
            break;
          }
          case 2: {
            if (id % 4 == 0) {
              // Binary garbage with its own line end, and an empty line.
              auto r = robot.request(garbage(rng, 1 + rng() % 600), 10s);
              expect("garbage", r && r->rfind("ERROR ", 0) == 0);
              r = robot.request("", 10s);
              expect("empty line", r && r->rfind("ERROR 14 ", 0) == 0);
            } else {
              auto r = robot.request(id % 2 ? "STATUS" : "list", 10s);
              expect("STATUS/LIST", r && r->rfind("OK ", 0) == 0);
            }
            break;
          }
          default: {
            if (id % 8 == 1 && i == 3) {
              // A 1 MB line: one ERROR 12, then the connection goes on.
              auto r = robot.request(std::string(1 << 20, 'A'), 20s);
              expect("1 MB line", r && r->rfind("ERROR 12 ", 0) == 0);
            } else {
              auto r = robot.request("GRASP 1 LIST", 10s);
              expect("GRASP LIST", r && *r == "OK 1 0.000 0.000 90.000");
            }
            break;
          }
        }
        ++replies;
      }
      // Some robots leave mid-request: half a line, or half of a huge one.
      if (id % 3 == 0) (void)robot.sendRaw("LOCATE 1");
      if (id % 3 == 1) (void)robot.sendRaw(std::string(300000, 'B'));
      robot.close();
    });
  }
  for (auto& t : robots) t.join();
  for (const auto& m : failures.messages) FAIL_CHECK(m);
  CHECK(failures.messages.empty());
  CHECK(replies.load() == 32 * 12);

  // Still serving, on a fresh connection and with every reply one line.
  auto after = vision.connect();
  CHECK(*after.request("PING", 5s) == "OK");
  auto located = after.request("LOCATE 1", 10s);
  REQUIRE(located);
  CHECK(locateMismatch(*located, located_alone) == "");
  CHECK(*readFile(calibration_path) == *calibration_before);
  CHECK(*readFile(model_path) == *model_before);
}
