// The robot cell end to end: a file camera whose image the test swaps by
// renaming, CALCAM on a disc of known size, STORE/LIST/DELETE/COMPUTE
// against a known robot-camera transform, LOCATE in robot coordinates, and
// all of it again after a restart of the vision app.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>

#include <opencv2/imgproc.hpp>
#include "picksight/codecs/codecs.hpp"

#include "cell_fixture.hpp"
#include "picksight/common/angles.hpp"
#include "picksight/common/text.hpp"
#include "scene_file.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::tool_support;
using namespace std::chrono_literals;

namespace {
constexpr int kShift = 4;  // sub-pixel bits for OpenCV drawing
constexpr int kSuper = 8;  // supersampling: exact edge coverage, unlike LINE_AA

cv::Mat background() { return cv::Mat(480, 640, CV_8UC1, cv::Scalar(200)); }

cv::Point fine(cv::Point2d p) { return supersampledPoint(p, kSuper, kShift); }

// Dark shapes drawn sharp at kSuper times the size, then averaged down.
struct Canvas {
  cv::Mat big{480 * kSuper, 640 * kSuper, CV_8UC1, cv::Scalar(200)};
  void disc(cv::Point2d centre, double radius_px) {
    cv::circle(big, fine(centre), static_cast<int>(std::lround(radius_px * kSuper * (1 << kShift))),
               cv::Scalar(40), cv::FILLED, cv::LINE_8, kShift);
  }
  void bar(cv::Point2d centre, double image_deg) {
    const cv::RotatedRect r(cv::Point2f(static_cast<float>(centre.x), static_cast<float>(centre.y)),
                            cv::Size2f(90, 30), static_cast<float>(image_deg));
    cv::Point2f corners[4];
    r.points(corners);
    std::vector<cv::Point> poly;
    for (const auto& c : corners) poly.push_back(fine(c));
    cv::fillConvexPoly(big, poly, cv::Scalar(40), cv::LINE_8, kShift);
  }
  cv::Mat image() const {
    cv::Mat out;
    cv::resize(big, out, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
    return out;
  }
};

// The camera's image file.
struct Scene : SceneFile {
  Scene() : SceneFile(background()) {}
};

std::string ask(LineClient& robot, const std::string& request) {
  auto reply = robot.request(request, 10s);
  REQUIRE(reply);
  return *reply;
}

// The camera's region once the camera has opened: until then (a loaded
// machine, the first moments after a start) a ROI read is ERROR 20, asked
// again as a client would, for up to 10 s.
std::string firstRoi(LineClient& robot) {
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  for (;;) {
    const std::string reply = ask(robot, "ROI");
    if (reply.rfind("ERROR 20 ", 0) != 0 || std::chrono::steady_clock::now() > deadline)
      return reply;
    std::this_thread::sleep_for(50ms);
  }
}

// The robot frame of the test: vision mm turned by 30 degrees and moved.
constexpr double kRz = 30.0;
const cv::Point2d kShiftMm(412.5, -120.25);
cv::Point2d toRobot(cv::Point2d vision) {
  const double a = kRz * M_PI / 180.0;
  return {std::cos(a) * vision.x - std::sin(a) * vision.y + kShiftMm.x,
          std::sin(a) * vision.x + std::cos(a) * vision.y + kShiftMm.y};
}
}  // namespace

TEST_CASE("a cell calibrated through the protocol locates in robot coordinates", "[e2e][cell]") {
  Scene scene;
  VideoServerProcess server({"--source", "cam0=file:" + scene.path, "--mode", "trigger"});
  char data[] = "/tmp/picksight-cell-data-XXXXXX";
  REQUIRE(::mkdtemp(data) != nullptr);
  const std::string data_dir = data;
  double mm_x = 0, mm_y = 0;
  std::string calibration_file;
  {
    VisionProcess vision(server, "cam0", data_dir);
    auto robot = vision.connect();
    CHECK(ask(robot, "STATUS").rfind("OK frame=vision-px scale=none ", 0) == 0);

    // Camera calibration: a disc of radius 10 mm imaged 40 px wide.
    CHECK(ask(robot, "CALCAM 10").rfind("ERROR 1 ", 0) == 0);  // empty scene
    Canvas two;
    two.disc({150, 150}, 40);
    two.disc({400, 300}, 40);
    scene.show(two.image());
    CHECK(ask(robot, "CALCAM 10").rfind("ERROR 2 ", 0) == 0);
    CHECK(ask(robot, "STORE 1 2").rfind("ERROR 2 ", 0) == 0);
    Canvas one;
    one.disc({320.3, 240.7}, 40);
    scene.show(one.image());
    const auto scale = replyNumbers(ask(robot, "CALCAM 10"), 2);
    mm_x = scale[0];
    mm_y = scale[1];
    CHECK(mm_x == Approx(0.25).epsilon(0.002));
    CHECK(mm_y == Approx(0.25).epsilon(0.002));
    CHECK(ask(robot, "STATUS").rfind("OK frame=vision-mm ", 0) == 0);

    // Robot-camera calibration: the robot holds the target at known places.
    const std::vector<cv::Point2d> pixels{
        {100.2, 90.6}, {520.8, 110.1}, {480.4, 400.3}, {130.7, 380.9}, {300.5, 250.2}};
    for (size_t i = 0; i < pixels.size(); ++i) {
      Canvas img;
      img.disc(pixels[i], 20);
      scene.show(img.image());
      const cv::Point2d r = toRobot({pixels[i].x * mm_x, -pixels[i].y * mm_y});
      CHECK(ask(robot, "STORE " + formatFixed(r.x, 4) + "," + formatFixed(r.y, 4)) ==
            "OK " + std::to_string(i + 1));
    }
    CHECK(ask(robot, "STORE 1 2").rfind("OK ", 0) == 0);  // a mis-touched point, id 6
    const std::string list = ask(robot, "LIST");
    CHECK(list.rfind("OK 6 1 ", 0) == 0);
    CHECK(splitFields(list, " ").size() == 2 + 6 * 5);
    CHECK(ask(robot, "DELETE 6") == "OK");
    const std::string missing = ask(robot, "DELETE 6");
    CHECK(missing.rfind("ERROR 40 ", 0) == 0);
    CHECK(missing.find('6') != std::string::npos);
    const auto t = replyNumbers(ask(robot, "COMPUTE"), 4);
    CHECK(t[0] == Approx(kShiftMm.x).margin(0.1));
    CHECK(t[1] == Approx(kShiftMm.y).margin(0.1));
    CHECK(t[2] == Approx(kRz).margin(0.05));
    CHECK(t[3] < 0.05);
    CHECK(ask(robot, "STATUS").rfind("OK frame=robot ", 0) == 0);

    // LOCATE: a bar (no model: the region's own pose) in robot coordinates.
    Canvas part;
    part.bar({250.4, 200.6}, 25.0);
    scene.show(part.image());
    const auto poses = parseLocateReply(ask(robot, "LOCATE 1"));
    REQUIRE(poses.size() == 1);
    const cv::Point2d expected = toRobot({250.4 * mm_x, -200.6 * mm_y});
    CHECK(poses[0].x == Approx(expected.x).margin(0.1));
    CHECK(poses[0].y == Approx(expected.y).margin(0.1));
    // Image angle 25 (clockwise on screen) is -25 in the vision frame; the
    // robot frame turns it by 30 more. A bar's axis has a period of 180.
    CHECK(angleDiffDeg(poses[0].rz, -25.0 + kRz, 180.0) < 0.05);
    calibration_file = data_dir + "/calibration.yaml";
    REQUIRE(std::filesystem::exists(calibration_file));
  }
  // A restart: everything reloaded from the data directory.
  VisionProcess again(server, "cam0", data_dir);
  auto robot = again.connect();
  const std::string status = ask(robot, "STATUS");
  CHECK(status.rfind("OK frame=robot ", 0) == 0);
  CHECK(status.find(" points=5 ") != std::string::npos);
  CHECK(splitFields(ask(robot, "LIST"), " ").size() == 2 + 5 * 5);
  const auto poses = parseLocateReply(ask(robot, "LOCATE 1"));
  REQUIRE(poses.size() == 1);
  const cv::Point2d expected = toRobot({250.4 * mm_x, -200.6 * mm_y});
  CHECK(poses[0].x == Approx(expected.x).margin(0.1));
  CHECK(poses[0].y == Approx(expected.y).margin(0.1));
  const std::string residuals = ask(robot, "RESIDUALS");
  CHECK(residuals.rfind("OK 5 ", 0) == 0);
  std::error_code ignored;
  std::filesystem::remove_all(data_dir, ignored);
}

TEST_CASE("camera settings pass through to the video server", "[e2e][cell]") {
  VideoServerProcess server(
      {"--source", "cam0=synthetic:width=640,height=480,parts=2", "--mode", "trigger"});
  VisionProcess vision(server);
  auto robot = vision.connect();
  // The synthetic camera has no exposure feature: every name was tried.
  const std::string exposure = ask(robot, "EXPOSURE 5000");
  CHECK(exposure.rfind("ERROR 22 ", 0) == 0);
  CHECK(firstRoi(robot) == "OK 0 0 640 480");
  CHECK(ask(robot, "ROI 100 50 320 240") == "OK");
  CHECK(ask(robot, "ROI") == "OK 100 50 320 240");
  CHECK(ask(robot, "ROI 10000 10000 5 5").rfind("ERROR 22 ", 0) == 0);
  CHECK(ask(robot, "ROI FULL") == "OK");
  CHECK(ask(robot, "ROI") == "OK 0 0 640 480");
  CHECK(ask(robot, "PING") == "OK");
}

TEST_CASE("a camera not open yet answers a ROI read with ERROR 20 and not zeros", "[e2e][cell]") {
  // A folder that is not there: the video server keeps retrying the camera,
  // which never opens, so its sensor's size is never known.
  VideoServerProcess server(
      {"--source", "cam0=dir:/nonexistent-picksight-frames", "--mode", "trigger"});
  VisionProcess vision(server);
  auto robot = vision.connect();
  const std::string roi = ask(robot, "ROI");
  INFO(roi);
  CHECK(roi.rfind("ERROR 20 ", 0) == 0);
  CHECK(roi.find("cam0 has not opened yet") != std::string::npos);
  CHECK(ask(robot, "PING") == "OK");
}
