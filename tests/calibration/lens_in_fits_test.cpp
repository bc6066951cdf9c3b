// The lens model applied where it exists: calibration points and located
// parts are undistorted before the robot-camera fit and the conversion to
// robot millimetres, on a synthetic grid seen through a barrel-distorted lens.
#include <catch2/catch.hpp>

#include "temp_dir.hpp"

#include <algorithm>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "picksight/calibration/camera_calibration.hpp"
#include "picksight/store/cell_calibration.hpp"

using namespace picksight::calibration;
using picksight::store::CellCalibration;
using picksight::store::CoordinateFrame;
using picksight::test::TempDir;

namespace {
constexpr double kMmPerPx = 0.25;
const RigidTransform kRobot{412.35, -87.6, 37.25, false};  // vision mm -> robot mm

// A 1280 x 960 camera whose lens bends the image's corners by about 20
// pixels (5 mm at 0.25 mm per pixel).
LensModel barrelLens() {
  LensModel lens;
  lens.image_size = cv::Size(1280, 960);
  lens.camera_matrix = cv::Matx33d(1400, 0, 640, 0, 1400, 480, 0, 0, 1);
  lens.distortion = {-0.08, 0.02, 0, 0, 0};
  lens.rms_reprojection_px = 0.1;
  lens.views = 10;
  return lens;
}

// Where the camera images a point whose ideal (distortion-free) pixel is `ideal`.
cv::Point2d distort(const LensModel& lens, cv::Point2d ideal) {
  const cv::Matx33d& k = lens.camera_matrix;
  const std::vector<cv::Point3d> ray{
      {(ideal.x - k(0, 2)) / k(0, 0), (ideal.y - k(1, 2)) / k(1, 1), 1}};
  std::vector<cv::Point2d> out;
  cv::projectPoints(ray, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(k), lens.distortion, out);
  return out.front();
}

// The robot position of what the ideal pixel shows (vision y points up the image).
cv::Point2d robotOf(cv::Point2d ideal) {
  return kRobot.apply({ideal.x * kMmPerPx, -ideal.y * kMmPerPx});
}

// STOREs a 6 x 5 grid of target positions over the image, as the STORE
// command does: the vision point through the frame of the moment, and the
// sensor pixel it was measured at.
void storeGrid(CellCalibration& cal, const LensModel& lens) {
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 5; ++j) {
      const cv::Point2d ideal(60 + 230.0 * i, 50 + 215.0 * j);
      const cv::Point2d pixel = distort(lens, ideal);
      auto geometry = cal.geometry();
      REQUIRE(geometry);
      REQUIRE(cal.addPoint({geometry->vision.toMm(pixel), robotOf(ideal)}, pixel));
    }
  }
}

// Worst robot-frame error of parts located anywhere in the image.
double worstPartError(const CellCalibration& cal, const LensModel& lens) {
  auto geometry = cal.geometry();
  REQUIRE(geometry);
  REQUIRE(geometry->frame() == CoordinateFrame::kRobot);
  double worst = 0;
  for (int i = 0; i <= 12; ++i) {
    for (int j = 0; j <= 9; ++j) {
      const cv::Point2d ideal(20 + 103.0 * i, 15 + 103.0 * j);
      const cv::Point2d mm = geometry->vision.toMm(distort(lens, ideal));
      const auto pose = geometry->toReply({mm.x, mm.y, 0});
      worst = std::max(worst, cv::norm(cv::Point2d(pose.x, pose.y) - robotOf(ideal)));
    }
  }
  return worst;
}
}  // namespace

TEST_CASE("stored points and located parts are undistorted by the lens model",
          "[calibration][lens]") {
  const LensModel lens = barrelLens();
  // The corner's pixel is bent by the amount the test means to see.
  CHECK(cv::norm(distort(lens, {0, 0}) - cv::Point2d(0, 0)) > 15);
  TempDir dir;
  SECTION("the lens model calibrated before STORE") {
    CellCalibration cal(dir.file("calibration.yaml"));
    REQUIRE(cal.load());
    REQUIRE(cal.setScale({kMmPerPx, kMmPerPx, 0}));
    REQUIRE(cal.setLens(lens));
    storeGrid(cal, lens);
    auto r = cal.compute(Method::kBest);
    REQUIRE(r);
    CHECK(r->rms < 0.001);
    CHECK(r->inliers == 30);
    CHECK(worstPartError(cal, lens) < 0.005);
  }
  SECTION("the lens model calibrated after STORE places the stored points again") {
    CellCalibration cal(dir.file("calibration.yaml"));
    REQUIRE(cal.load());
    REQUIRE(cal.setScale({kMmPerPx, kMmPerPx, 0}));
    storeGrid(cal, lens);
    REQUIRE(cal.setLens(lens));
    // LIST shows (and COMPUTE fits) the points as the lens model places them.
    const auto points = cal.points();
    REQUIRE(points.count(1));
    CHECK(cv::norm(points.at(1).vision - cv::Point2d(60 * kMmPerPx, -50 * kMmPerPx)) < 1e-4);
    auto r = cal.compute(Method::kBest);
    REQUIRE(r);
    CHECK(r->rms < 0.001);
    CHECK(worstPartError(cal, lens) < 0.005);
    // And so after a restart: the pixels are in the calibration file.
    CellCalibration again(dir.file("calibration.yaml"));
    REQUIRE(again.load());
    CHECK(cv::norm(again.points().at(1).vision - points.at(1).vision) < 1e-9);
    CHECK(worstPartError(again, lens) < 0.005);
  }
  SECTION("without the lens model the same cell is millimetres off") {
    CellCalibration cal(dir.file("calibration.yaml"));
    REQUIRE(cal.load());
    REQUIRE(cal.setScale({kMmPerPx, kMmPerPx, 0}));
    storeGrid(cal, lens);
    auto r = cal.compute(Method::kBest);
    REQUIRE(r);
    CHECK(r->rms > 0.3);
    CHECK(worstPartError(cal, lens) > 1.0);
  }
}

TEST_CASE("a lens model without CALCAM undistorts pixels in the pixel frame",
          "[calibration][lens]") {
  const LensModel lens = barrelLens();
  TempDir dir;
  CellCalibration cal(dir.file("calibration.yaml"));
  REQUIRE(cal.load());
  REQUIRE(cal.setLens(lens));
  auto geometry = cal.geometry();
  REQUIRE(geometry);
  CHECK(geometry->frame() == CoordinateFrame::kVisionPixels);
  for (const cv::Point2d ideal :
       {cv::Point2d(0, 0), cv::Point2d(1279, 959), cv::Point2d(640, 10)}) {
    INFO(ideal);
    CHECK(cv::norm(geometry->vision.toMm(distort(lens, ideal)) - cv::Point2d(ideal.x, -ideal.y)) <
          0.001);
  }
}
