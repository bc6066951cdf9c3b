// The simulated robot: its hidden transform as the robot protocol states it,
// and the calibration target drawn where the transform says, with the size
// asked, exactly enough for a calibration to be checked against it.
#include <catch2/catch.hpp>

#include <cmath>

#include "picksight/synthetic/scene.hpp"
#include "picksight/synthetic/simulated_robot.hpp"

using namespace picksight::synthetic;

namespace {

// robot = R(rz) * (u * s, -v * s) + (dx, dy): docs/PROTOCOL.md's frames.
cv::Point2d protocolRobot(const RobotCamera& c, cv::Point2d pixel) {
  const double a = c.rz_deg * M_PI / 180;
  const double xv = pixel.x * c.mm_per_px;
  const double yv = -pixel.y * c.mm_per_px;
  return {std::cos(a) * xv - std::sin(a) * yv + c.dx_mm,
          std::sin(a) * xv + std::cos(a) * yv + c.dy_mm};
}

RobotCamera hiddenCamera() {
  RobotCamera c;
  c.mm_per_px = 0.25;
  c.rz_deg = 178.7;
  c.dx_mm = 330.5;
  c.dy_mm = -612.25;
  return c;
}

// Grey-level centroid and area of the darkening in a flat-lit, noise-free
// image: exact for the coverage drawn.
struct Darkening {
  cv::Point2d centroid;
  double area = 0;
};
Darkening darkening(const cv::Mat& image, double background, double level) {
  double sum = 0, sx = 0, sy = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const double w = (background - image.at<float>(y, x)) / (background - level);
      sum += w;
      sx += w * x;
      sy += w * y;
    }
  }
  return {{sx / sum, sy / sum}, sum};
}

}  // namespace

TEST_CASE("the hidden transform is the robot protocol's frame chain", "[synthetic][robot]") {
  const RobotCamera camera = hiddenCamera();
  const RobotCameraModel model(camera, 1280, 960);
  for (const cv::Point2d pixel : {cv::Point2d(0, 0), cv::Point2d(640.25, 480.5),
                                  cv::Point2d(1279, 17.75), cv::Point2d(3, 959)}) {
    const cv::Point2d robot = protocolRobot(camera, pixel);
    const cv::Point2d back = model.toImage(robot);
    CHECK(back.x == Approx(pixel.x).margin(1e-9));
    CHECK(back.y == Approx(pixel.y).margin(1e-9));
    const cv::Point2d again = model.toRobot(pixel);
    CHECK(again.x == Approx(robot.x).margin(1e-9));
    CHECK(again.y == Approx(robot.y).margin(1e-9));
  }
}

TEST_CASE("a tilted camera keeps the scale at the image centre and bends the rest",
          "[synthetic][robot]") {
  RobotCamera camera = hiddenCamera();
  camera.tilt_x_deg = 2;
  camera.tilt_y_deg = -1;
  const RobotCameraModel tilted(camera, 1280, 960);
  const RobotCameraModel flat(hiddenCamera(), 1280, 960);
  const cv::Point2d centre(639.5, 479.5);
  CHECK(cv::norm(tilted.toRobot(centre) - flat.toRobot(centre)) < 1e-9);
  // One pixel across the centre spans mm_per_px, to first order.
  const double step = cv::norm(tilted.toRobot(centre + cv::Point2d(0.5, 0)) -
                               tilted.toRobot(centre - cv::Point2d(0.5, 0)));
  CHECK(step == Approx(0.25).epsilon(1e-4));
  // At the left edge the perspective moves points by a few pixels.
  const cv::Point2d edge(0, 479.5);
  CHECK(cv::norm(tilted.toImage(flat.toRobot(edge)) - edge) > 2);
  // Round trip through the homography.
  const cv::Point2d p(100, 900);
  CHECK(cv::norm(tilted.toImage(tilted.toRobot(p)) - p) < 1e-9);
}

TEST_CASE("a target disc is drawn where the transform puts it, at its size", "[synthetic][robot]") {
  const RobotCameraModel model(hiddenCamera(), 400, 300);
  CalibrationTarget target;
  target.radius_mm = 5;  // 20 px
  for (const cv::Point2d at : {model.toRobot({200.3, 150.7}), model.toRobot({100.05, 80.5})}) {
    cv::Mat image(300, 400, CV_32F, cv::Scalar(200));
    const auto truth = drawTarget(image, cv::Mat(), model, target, at, 45);
    REQUIRE(truth.size() == 1);
    const cv::Point2d expected = model.toImage(at);
    CHECK(cv::norm(truth[0].image_px - expected) < 1e-9);
    const Darkening d = darkening(image, 200, 45);
    // Exact to the supersampling: far below 1/100 px and 0.1 % of the area.
    CHECK(std::abs(d.centroid.x - expected.x) < 0.002);
    CHECK(std::abs(d.centroid.y - expected.y) < 0.002);
    CHECK(d.area == Approx(M_PI * 20 * 20).epsilon(1e-3));
    CHECK(d.area == Approx(truth[0].area_px).epsilon(1e-6));
  }
}

TEST_CASE("a dot grid target lays its dots along the robot axes", "[synthetic][robot]") {
  const RobotCameraModel model(hiddenCamera(), 640, 480);
  CalibrationTarget grid;
  grid.kind = TargetKind::kGrid;
  grid.cols = 4;
  grid.rows = 3;
  grid.pitch_mm = 15;
  grid.radius_mm = 3;
  const cv::Point2d at = model.toRobot({320, 240});
  cv::Mat image(480, 640, CV_32F, cv::Scalar(200));
  const auto truth = drawTarget(image, cv::Mat(), model, grid, at, 45);
  REQUIRE(truth.size() == 12);
  CHECK(truth[0].robot_mm.x == Approx(at.x - 22.5));
  CHECK(truth[0].robot_mm.y == Approx(at.y - 15));
  CHECK(truth[11].robot_mm.x == Approx(at.x + 22.5));
  CHECK(truth[11].robot_mm.y == Approx(at.y + 15));
  // Neighbouring dots are pitch / mm_per_px pixels apart.
  CHECK(cv::norm(truth[1].image_px - truth[0].image_px) == Approx(60).epsilon(1e-9));
  for (const auto& dot : truth) CHECK(dot.area_px == Approx(M_PI * 12 * 12).epsilon(2e-3));
}

TEST_CASE("a scene shows and hides the target over its parts", "[synthetic][robot]") {
  SceneOptions o = sceneOptions(320, 240, 2, 7);
  o.noise_sigma = 0;
  SceneRenderer scene(o);
  const cv::Mat before = scene.clean().clone();
  CHECK(scene.targetTruth().empty());
  const RobotCamera camera = hiddenCamera();
  const RobotCameraModel model(camera, 320, 240);
  CalibrationTarget disc;
  disc.radius_mm = 4;
  scene.setTarget(camera, disc, model.toRobot({160, 120}));
  REQUIRE(scene.targetTruth().size() == 1);
  CHECK(scene.targetTruth()[0].image_px.x == Approx(160));
  CHECK(scene.clean().at<uint8_t>(120, 160) < 60);
  CHECK(cv::norm(scene.clean(), before, cv::NORM_L1) > 0);
  CHECK(scene.truth().size() == 2);  // the parts stay
  scene.setTarget(camera, disc, std::nullopt);
  CHECK(scene.targetTruth().empty());
  CHECK(cv::norm(scene.clean(), before, cv::NORM_INF) == 0);
}
