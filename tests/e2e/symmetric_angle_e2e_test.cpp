// The same part in the same place gives the same angle, through the robot
// protocol: a bar (a half-turn-symmetric part) lying still under the
// synthetic camera, fresh sensor noise in every frame, LOCATE and LOCATE
// ALL over real TCP from a real video server and vision app.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "cell_fixture.hpp"
#include "picksight/common/text.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::tool_support;
using namespace std::chrono_literals;

namespace {
std::string ask(LineClient& robot, const std::string& request) {
  auto reply = robot.request(request, 20s);
  REQUIRE(reply);
  return *reply;
}

// The rz of the one part of "OK 1 [type] x y rz".
double onlyRz(const std::string& reply, bool with_type) {
  INFO(reply);
  const auto w = splitFields(reply, " ");
  REQUIRE(w.size() == (with_type ? 6u : 5u));
  REQUIRE(w[0] == "OK");
  REQUIRE(w[1] == "1");
  if (with_type) REQUIRE(w[2] == "1");
  const auto rz = parseDouble(w.back());
  REQUIRE(rz);
  return *rz;
}
}  // namespace

TEST_CASE("a bar lying still at its taught angle gets one rz in every LOCATE",
          "[e2e][locate][symmetry]") {
  // One rectangle (a bar: alike turned by 180 degrees), taught where it
  // lies; every frame of the synthetic camera has noise of its own. Before
  // the rule, 19 of 100 LOCATEs here said 0.0 and 81 said 180.0.
  VideoServerProcess server({"--source",
                             "cam0=synthetic:width=640,height=480,parts=1,types=rectangle,seed=4",
                             "--mode", "trigger"});
  VisionProcess vision(server);
  auto robot = vision.connect();
  const std::string learned = ask(robot, "LEARN 1 bar");
  INFO(learned);
  const auto fields = splitFields(learned, " ");
  REQUIRE(fields.size() >= 7);
  REQUIRE(fields[0] == "OK");
  REQUIRE(fields[5] == "180.000");  // the model's symmetry
  std::vector<double> rz;
  for (int i = 0; i < 40; ++i) {
    const bool all = i % 2 == 1;
    rz.push_back(onlyRz(ask(robot, all ? "LOCATE ALL" : "LOCATE 1"), all));
  }
  const auto [lo, hi] = std::minmax_element(rz.begin(), rz.end());
  INFO("rz from " << *lo << " to " << *hi);
  // Within noise of one value, and that value the taught angle (0 in the
  // vision frame the uncalibrated cell replies in): never 180 apart.
  CHECK(*hi - *lo < 0.3);
  CHECK(std::abs(*lo) < 0.3);
  CHECK(std::abs(*hi) < 0.3);
}
