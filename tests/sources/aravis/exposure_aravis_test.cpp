// EXPOSURE through the whole chain on a real GenICam device: robot ->
// picksight-vision -> picksight-video-server -> Aravis -> Aravis's fake GigE
// camera, which names its exposure ExposureTimeAbs (older GenICam).
#include <catch2/catch.hpp>

#include "cell_fixture.hpp"
#include "fake_gv_camera.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace std::chrono_literals;

TEST_CASE("EXPOSURE finds the camera's exposure feature by its usual names", "[cell][camera]") {
  test::FakeGvCamera fake;
  VideoServerProcess server(
      {"--source", std::string("cam0=aravis:") + test::FakeGvCamera::kDeviceId, "--fps", "10"});
  VisionProcess vision(server);
  auto robot = vision.connect();
  auto reply = robot.request("EXPOSURE 15000", 10s);
  REQUIRE(reply);
  CHECK(*reply == "OK ExposureTimeAbs 15000");
  reply = robot.request("exposure", 10s);
  REQUIRE(reply);
  CHECK(*reply == "OK ExposureTimeAbs 15000");
  // Below the feature's minimum (10 us): the camera's own reason, not "unknown".
  reply = robot.request("EXPOSURE 1", 10s);
  REQUIRE(reply);
  CHECK(reply->rfind("ERROR 22 ", 0) == 0);
  CHECK(reply->find("ExposureTimeAbs") != std::string::npos);
}
