// A dot grid seen by a tilted camera through a distorting lens: the fitted
// homography and radial terms make the vision frame exact millimetres on
// the plane, everywhere, not only at the dots; and they survive the file.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <random>

#include <opencv2/calib3d.hpp>

#include "picksight/calibration/calibration_store.hpp"
#include "picksight/calibration/dot_grid_model.hpp"
#include "picksight/calibration/robot_camera.hpp"
#include "picksight/calibration/vision_frame.hpp"
#include "temp_dir.hpp"

using namespace picksight::calibration;

namespace {

// A camera 1000 mm above the plane, tilted about an in-plane axis, focal
// length 4000 px (0.25 mm/px straight down), with radial distortion k1 of
// the normalized (focal-length) coordinates, on a 1920 x 1080 sensor.
struct Camera {
  double tilt_deg = 2;
  double tilt_axis_deg = 30;
  double k1 = 0;
  cv::Size sensor{1920, 1080};
  double f = 4000;
  double height = 1000;

  cv::Point2d ideal(cv::Point2d plane_mm) const {
    const double a = tilt_axis_deg * M_PI / 180, t = tilt_deg * M_PI / 180;
    cv::Matx33d r;
    cv::Rodrigues(cv::Vec3d(std::cos(a), std::sin(a), 0) * t, r);
    const cv::Vec3d c = r * cv::Vec3d(plane_mm.x, plane_mm.y, 0) + cv::Vec3d(0, 0, height);
    return {c[0] / c[2], c[1] / c[2]};  // normalized image coordinates
  }
  cv::Point2d pixel(cv::Point2d plane_mm) const {
    const cv::Point2d u = ideal(plane_mm);
    const double r2 = u.dot(u);
    const cv::Point2d d = u * (1 + k1 * r2);
    return {f * d.x + (sensor.width - 1) / 2.0, f * d.y + (sensor.height - 1) / 2.0};
  }
};

struct Grid {
  std::vector<cv::Point2d> centres;
  std::vector<cv::Point2i> indices;
};

Grid imageGrid(const Camera& cam, int cols, int rows, double pitch, double noise_px) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n(0, noise_px);
  Grid g;
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < cols; ++i) {
      const cv::Point2d plane((i - (cols - 1) / 2.0) * pitch, (j - (rows - 1) / 2.0) * pitch);
      g.centres.push_back(cam.pixel(plane) + cv::Point2d(n(rng), n(rng)));
      g.indices.emplace_back(i, j);
    }
  }
  return g;
}

// How far the vision frame is from the plane over the whole field: the
// RMS of a rigid fit (the vision frame's place on the plane is free)
// between vision millimetres and plane millimetres at points between the dots.
double fieldError(const Camera& cam, const VisionFrame& frame) {
  std::vector<PointPair> pairs;
  for (int i = 0; i <= 20; ++i) {
    for (int j = 0; j <= 10; ++j) {
      const cv::Point2d plane(-205 + 20.5 * i, -112 + 22.4 * j);
      pairs.push_back({frame.toMm(cam.pixel(plane)), plane});
    }
  }
  auto fit = calibrate(pairs, Method::kLeastSquares);
  REQUIRE(fit);
  return fit->rms;
}

}  // namespace

TEST_CASE("a dot grid takes a 2 degree tilt and barrel distortion out of the vision frame",
          "[calibration]") {
  Camera cam;
  cam.k1 = -0.08;  // about 11 px at the sensor's corners
  const Grid g = imageGrid(cam, 17, 9, 25, 0.02);
  auto model = fitDotGrid(g.centres, g.indices, 25, std::nullopt, cam.sensor);
  REQUIRE(model);
  REQUIRE(model->lens);
  REQUIRE(model->scale.rectify);
  CHECK(model->rms_px < 0.05);
  CHECK(model->perspective_px > 5);  // the tilt is seen
  CHECK(model->scale.mm_per_px_x == Approx(0.25).epsilon(0.01));
  CHECK(model->scale.mm_per_px_x == model->scale.mm_per_px_y);

  const double with_model = fieldError(cam, VisionFrame(model->scale, model->lens));
  // The scale alone, as CALCAM with a disc gives it: tilt and lens left in.
  PixelScale plain = model->scale;
  plain.rectify.reset();
  const double scale_only = fieldError(cam, VisionFrame(plain));
  INFO("field RMS: grid model " << with_model << " mm, scale only " << scale_only << " mm");
  CHECK(with_model < 0.01);
  CHECK(scale_only > 0.3);
}

TEST_CASE("a grid in part of the sensor fits the tilt but no lens", "[calibration]") {
  Camera cam;
  cam.tilt_axis_deg = -75;
  const Grid g = imageGrid(cam, 7, 5, 25, 0.02);  // about 600 x 400 px in the middle
  auto model = fitDotGrid(g.centres, g.indices, 25, std::nullopt, cam.sensor);
  REQUIRE(model);
  CHECK_FALSE(model->lens);
  REQUIRE(model->scale.rectify);
  CHECK(fieldError(cam, VisionFrame(model->scale)) < 0.01);
  // Without the sensor's size (a cropped or resized camera) no lens, even
  // from dots over the whole sensor (which fit one when its size is given).
  const Grid wide = imageGrid(cam, 17, 9, 25, 0.02);
  auto sized = fitDotGrid(wide.centres, wide.indices, 25, std::nullopt, cam.sensor);
  REQUIRE(sized);
  CHECK(sized->lens);
  auto cropped = fitDotGrid(wide.centres, wide.indices, 25, std::nullopt, std::nullopt);
  REQUIRE(cropped);
  CHECK_FALSE(cropped->lens);
}

TEST_CASE("a lens is fitted from dots reaching 60 % of the way to the sensor's corners",
          "[calibration]") {
  // The grid's pitch is about 100 px: 11 x 5 dots reach 0.49 of the
  // half-diagonal (1101 px), 15 x 7 reach 0.69. The reach, not the
  // distortion seen, decides.
  Camera cam;
  cam.k1 = -0.08;
  const auto reachOf = [&](const Grid& g) {
    const cv::Point2d middle((cam.sensor.width - 1) / 2.0, (cam.sensor.height - 1) / 2.0);
    double reach = 0;
    for (const auto& c : g.centres) reach = std::max(reach, cv::norm(c - middle));
    return reach / (std::hypot(cam.sensor.width, cam.sensor.height) / 2);
  };
  const Grid inner = imageGrid(cam, 11, 5, 25, 0.02);
  const Grid outer = imageGrid(cam, 15, 7, 25, 0.02);
  INFO("reach " << reachOf(inner) << " and " << reachOf(outer) << " of the half-diagonal");
  REQUIRE(reachOf(inner) < 0.52);
  REQUIRE(reachOf(outer) > 0.66);
  auto short_reach = fitDotGrid(inner.centres, inner.indices, 25, std::nullopt, cam.sensor);
  REQUIRE(short_reach);
  CHECK_FALSE(short_reach->lens);
  auto long_reach = fitDotGrid(outer.centres, outer.indices, 25, std::nullopt, cam.sensor);
  REQUIRE(long_reach);
  REQUIRE(long_reach->lens);
  CHECK(long_reach->rms_px < 0.05);
  CHECK(long_reach->lens->distortion[0] < 0);  // barrel, as drawn
}

TEST_CASE("a camera looking straight down gets an identity rectification and the orientation kept",
          "[calibration]") {
  Camera cam;
  cam.tilt_deg = 0;
  // The grid's own handedness must not mirror the vision frame: index the
  // rows the other way round.
  Grid g = imageGrid(cam, 9, 6, 25, 0);
  for (auto& ij : g.indices) ij.y = 5 - ij.y;
  auto model = fitDotGrid(g.centres, g.indices, 25, std::nullopt, std::nullopt);
  REQUIRE(model);
  REQUIRE(model->scale.rectify);
  for (const cv::Point2d p :
       {cv::Point2d(10, 10), cv::Point2d(1900, 1070), cv::Point2d(960, 540)}) {
    const cv::Vec3d q = *model->scale.rectify * cv::Vec3d(p.x, p.y, 1);
    CHECK(q[0] / q[2] == Approx(p.x).margin(1e-6));
    CHECK(q[1] / q[2] == Approx(p.y).margin(1e-6));
  }
  CHECK(model->perspective_px < 1e-6);
}

TEST_CASE("fewer than 3 x 3 dots give a scale without rectification, bad input an error",
          "[calibration]") {
  Camera cam;
  const Grid g = imageGrid(cam, 2, 2, 25, 0);
  auto model = fitDotGrid(g.centres, g.indices, 25, std::nullopt, cam.sensor);
  REQUIRE(model);
  CHECK_FALSE(model->scale.rectify);
  CHECK_FALSE(model->lens);
  CHECK(model->scale.mm_per_px_x == Approx(0.25).epsilon(0.01));
  // Pixels 2 % taller than wide, the grid turned 30 degrees: X and Y apart.
  std::vector<cv::Point2d> tall;
  for (const auto& ij : g.indices) {
    const double a = 30 * M_PI / 180, x = ij.x * 25 / 0.25, y = ij.y * 25 / 0.25;
    tall.emplace_back(100 + std::cos(a) * x - std::sin(a) * y,
                      100 + (std::sin(a) * x + std::cos(a) * y) / 1.02);
  }
  auto anisotropic = fitDotGrid(tall, g.indices, 25, std::nullopt, std::nullopt);
  REQUIRE(anisotropic);
  CHECK(anisotropic->scale.mm_per_px_x == Approx(0.25).epsilon(1e-9));
  CHECK(anisotropic->scale.mm_per_px_y == Approx(0.255).epsilon(1e-9));
  CHECK_FALSE(fitDotGrid(g.centres, g.indices, 0, std::nullopt, std::nullopt));
  CHECK_FALSE(fitDotGrid({g.centres[0]}, {g.indices[0]}, 25, std::nullopt, std::nullopt));
}

TEST_CASE("the rectification is stored exactly and a damaged one is refused", "[calibration]") {
  picksight::test::TempDir dir;
  const std::string path = dir.file("calibration.yaml");
  Camera cam;
  const Grid g = imageGrid(cam, 9, 6, 25, 0.02);
  auto model = fitDotGrid(g.centres, g.indices, 25, std::nullopt, std::nullopt);
  REQUIRE(model);
  {
    CalibrationStore store(path);
    REQUIRE(store.load());
    REQUIRE(store.setScale(model->scale));
  }
  CalibrationStore again(path);
  REQUIRE(again.load());
  REQUIRE(again.scale());
  REQUIRE(again.scale()->rectify);
  for (int i = 0; i < 9; ++i) CHECK(again.scale()->rectify->val[i] == model->scale.rectify->val[i]);

  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto at = text.find("rectify: [");
  REQUIRE(at != std::string::npos);
  const auto comma = text.find(',', at);
  REQUIRE(comma != std::string::npos);
  text.replace(at + 10, comma - at - 10, ".nan");  // the first value
  {
    std::ofstream out(path);
    out << text;
  }
  CalibrationStore damaged(path);
  const auto loaded = damaged.load();
  REQUIRE_FALSE(loaded);
  CHECK(loaded.error().message.find("scale.rectify is not all finite") != std::string::npos);
}

TEST_CASE("directions parallel on the plane are parallel in the rectified vision frame",
          "[calibration]") {
  Camera cam;
  cam.tilt_axis_deg = 0;  // the perspective runs along the image's y
  const Grid g = imageGrid(cam, 17, 9, 25, 0.0);
  auto model = fitDotGrid(g.centres, g.indices, 25, std::nullopt, cam.sensor);
  REQUIRE(model);
  const VisionFrame frame(model->scale, model->lens);
  // The plane's y axis (across the tilt's axis: such lines converge in the
  // image), imaged at the left and at the right of the field.
  double image[2], vision[2];
  int k = 0;
  for (const double x : {-180.0, 180.0}) {
    const cv::Point2d a = cam.pixel({x, -100}), b = cam.pixel({x, 100});
    const cv::Point2d d = b - a;
    image[k] = std::atan2(d.y, d.x) * 180 / M_PI;
    const cv::Point2d at = cam.pixel({x, 0});
    const cv::Point2d s = cam.pixel({x, 0.5}) - cam.pixel({x, -0.5});
    vision[k] = frame.directionToVision(std::atan2(s.y, s.x) * 180 / M_PI, at);
    ++k;
  }
  INFO("image directions " << image[0] << ", " << image[1] << "; vision " << vision[0] << ", "
                           << vision[1]);
  CHECK(std::abs(image[0] - image[1]) > 0.3);  // the tilt turns them in the image
  CHECK(std::abs(vision[0] - vision[1]) < 0.01);
}
