// Grasp poses and finger clearance.
#include <catch2/catch.hpp>

#include <opencv2/imgproc.hpp>

#include "picksight/grasp/grasp.hpp"

using namespace picksight;
using namespace picksight::grasp;

namespace {
// 1 mm per pixel: vision mm (x, y) is pixel (x, -y).
const calibration::VisionFrame kFrame(calibration::PixelScale{1.0, 1.0, 0});

// A two-finger parallel gripper: fingers 10 x 6 mm, 40 mm apart along y.
Gripper parallelGripper() { return Gripper{{Finger{0, 20, 10, 6}, Finger{0, -20, 10, 6}}}; }
}  // namespace

TEST_CASE("a grasp style turns and moves with the part", "[grasp]") {
  const Pose g = gripperPose({100, -50, 90}, {10, 0, 15});
  CHECK(g.x == Approx(100));
  CHECK(g.y == Approx(-40));
  CHECK(g.rz_deg == Approx(105));
  CHECK(gripperPose({0, 0, 350}, {0, 0, 20}).rz_deg == Approx(10));
}

TEST_CASE("finger footprints land where the fingers are", "[grasp]") {
  const auto polys = fingerPolygons({200, -100, 0}, parallelGripper(), kFrame);
  REQUIRE(polys.size() == 2);
  // First finger centred at vision (200, -80): pixel (200, 80).
  cv::Point2d centre(0, 0);
  for (const auto& p : polys[0]) centre += p / 4.0;
  CHECK(centre.x == Approx(200));
  CHECK(centre.y == Approx(80));
}

TEST_CASE("a grasp whose fingers cover another part is not offered and the next clear one is",
          "[grasp]") {
  Obstacles obstacles;
  obstacles.mask = cv::Mat(300, 400, CV_8UC1, cv::Scalar(0));
  // Another part right beside the first finger's spot of style 0.
  cv::rectangle(obstacles.mask, cv::Rect(190, 70, 20, 8), cv::Scalar(255), cv::FILLED);
  const Pose part{200, -100, 0};
  const std::vector<GraspStyle> styles = {{0, 0, 0}, {0, 0, 90}};
  CHECK_FALSE(fingersClear(gripperPose(part, styles[0]), parallelGripper(), kFrame, obstacles));
  CHECK(fingersClear(gripperPose(part, styles[1]), parallelGripper(), kFrame, obstacles));
  CHECK(firstClearGrasp(part, styles, parallelGripper(), kFrame, obstacles) == 1u);
  // Blocked both ways: no grasp.
  cv::rectangle(obstacles.mask, cv::Rect(215, 95, 10, 10), cv::Scalar(255), cv::FILLED);
  CHECK_FALSE(firstClearGrasp(part, styles, parallelGripper(), kFrame, obstacles));
  // No styles: nothing to offer.
  CHECK_FALSE(firstClearGrasp(part, {}, parallelGripper(), kFrame, obstacles));
}

TEST_CASE("a finger outside the image counts as blocked", "[grasp]") {
  Obstacles obstacles;
  obstacles.mask = cv::Mat(300, 400, CV_8UC1, cv::Scalar(0));
  CHECK(fingersClear({200, -150, 0}, parallelGripper(), kFrame, obstacles));
  CHECK_FALSE(fingersClear({200, -10, 0}, parallelGripper(), kFrame, obstacles));
}

TEST_CASE("obstacles in a resized frame are checked through the frame's mapping", "[grasp]") {
  Obstacles obstacles;
  obstacles.mask = cv::Mat(150, 200, CV_8UC1, cv::Scalar(0));  // half size
  obstacles.sensor_to_mask = cv::Matx23d(0.5, 0, -0.25, 0, 0.5, -0.25);
  // The part at sensor (190..210, 70..78) appears at half scale.
  cv::rectangle(obstacles.mask, cv::Rect(95, 35, 10, 4), cv::Scalar(255), cv::FILLED);
  CHECK_FALSE(fingersClear({200, -100, 0}, parallelGripper(), kFrame, obstacles));
  CHECK(fingersClear({200, -100, 90}, parallelGripper(), kFrame, obstacles));
}

TEST_CASE("one obstacle pixel under any corner of a finger blocks it", "[grasp]") {
  // Finger 1 of style 0 at part (200, -100): pixels x 195..205, y 77..83.
  for (const cv::Point corner : {cv::Point(196, 78), cv::Point(204, 78), cv::Point(204, 82),
                                 cv::Point(196, 82), cv::Point(200, 80)}) {
    INFO("obstacle pixel " << corner);
    Obstacles obstacles;
    obstacles.mask = cv::Mat(300, 400, CV_8UC1, cv::Scalar(0));
    obstacles.mask.at<uint8_t>(corner) = 255;
    CHECK_FALSE(fingersClear({200, -100, 0}, parallelGripper(), kFrame, obstacles));
  }
  // ... and one just beside it does not.
  Obstacles beside;
  beside.mask = cv::Mat(300, 400, CV_8UC1, cv::Scalar(0));
  beside.mask.at<uint8_t>(cv::Point(207, 80)) = 255;
  CHECK(fingersClear({200, -100, 0}, parallelGripper(), kFrame, beside));
}

TEST_CASE("a finger 2 px past the image edge is blocked and one at the edge is not", "[grasp]") {
  Obstacles obstacles;
  obstacles.mask = cv::Mat(300, 400, CV_8UC1, cv::Scalar(0));
  // Fingers 10 mm wide about x: from x - 5 to x + 5 pixels.
  CHECK_FALSE(fingersClear({3, -150, 0}, parallelGripper(), kFrame, obstacles));
  CHECK(fingersClear({5, -150, 0}, parallelGripper(), kFrame, obstacles));
  CHECK_FALSE(fingersClear({397, -150, 0}, parallelGripper(), kFrame, obstacles));
  CHECK(fingersClear({394, -150, 0}, parallelGripper(), kFrame, obstacles));
}
