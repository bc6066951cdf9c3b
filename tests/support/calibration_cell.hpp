// A synthetic robot-camera cell for calibration tests and the calibration
// benchmark: a camera above the work plane (optionally tilted, its scale
// optionally wrong), a robot frame at any rotation (optionally mirrored),
// point pairs with noise and outliers, and the exact vision-to-robot map to
// judge a fitted transform against.
#pragma once

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "picksight/calibration/robot_camera.hpp"

namespace picksight::test {

struct CellSpec {
  double field_w = 360;  // work area seen by the camera, mm
  double field_h = 170;
  double camera_height = 800;  // mm above the plane
  double tilt_deg = 0;         // camera tilt from looking straight down
  double tilt_axis_deg = 30;   // direction of the tilt's axis in the plane
  double scale_error = 0;      // vision mm = true mm * (1 + scale_error)
  calibration::RigidTransform robot{412.35, -87.6, 37.25, false};  // plane -> robot
  int points = 7;
  double robot_noise = 0.05;  // mm, standard deviation per coordinate
  double vision_noise = 0.0;
  int outliers = 0;  // robot points off by 2 to 20 mm
  uint64_t seed = 1;
};

struct CalibrationCell {
  CellSpec spec;
  cv::Matx33d plane_to_vision;
  cv::Matx33d vision_to_robot;  // the exact truth
  std::vector<calibration::PointPair> points;
  std::vector<bool> outlier;

  cv::Point2d truth(cv::Point2d vision) const {
    const cv::Vec3d q = vision_to_robot * cv::Vec3d(vision.x, vision.y, 1);
    return {q[0] / q[2], q[1] / q[2]};
  }
  cv::Point2d toVision(cv::Point2d plane) const {
    const cv::Vec3d q = plane_to_vision * cv::Vec3d(plane.x, plane.y, 1);
    return {q[0] / q[2], q[1] / q[2]};
  }

  // Misplacement of a part located anywhere in the work area (a 21 x 11
  // grid over it): every distance, mm.
  std::vector<double> placementErrors(const calibration::PlaneTransform& fit) const {
    std::vector<double> out;
    for (int i = 0; i <= 20; ++i) {
      for (int j = 0; j <= 10; ++j) {
        const cv::Point2d plane((i / 20.0 - 0.5) * spec.field_w, (j / 10.0 - 0.5) * spec.field_h);
        const cv::Point2d v = toVision(plane);
        out.push_back(cv::norm(fit.apply(v) - truth(v)));
      }
    }
    return out;
  }
  double placementRms(const calibration::PlaneTransform& fit) const {
    double s = 0;
    const auto e = placementErrors(fit);
    for (double d : e) s += d * d;
    return std::sqrt(s / static_cast<double>(e.size()));
  }
};

inline CalibrationCell makeCalibrationCell(const CellSpec& spec) {
  CalibrationCell cell;
  cell.spec = spec;
  // The camera looks down from (0, 0, height), turned by the tilt about an
  // axis in the plane; vision mm = height * (x, y) / depth, scaled by the
  // scale error (no tilt, no error: vision = plane).
  const double a = spec.tilt_axis_deg * M_PI / 180, t = spec.tilt_deg * M_PI / 180;
  cv::Vec3d axis(std::cos(a), std::sin(a), 0);
  cv::Matx33d rot;
  cv::Rodrigues(axis * t, rot);
  const cv::Vec3d centre(0, 0, spec.camera_height);
  const cv::Vec3d rc = rot * centre;
  const cv::Matx33d plane_to_camera(rot(0, 0), rot(0, 1), -rc[0], rot(1, 0), rot(1, 1), -rc[1],
                                    rot(2, 0), rot(2, 1), -rc[2]);
  const double k = spec.camera_height * (1 + spec.scale_error);
  cell.plane_to_vision = cv::Matx33d(k, 0, 0, 0, k, 0, 0, 0, -1) * plane_to_camera;
  const double r = spec.robot.rz_deg * M_PI / 180, m = spec.robot.mirrored ? -1.0 : 1.0;
  const cv::Matx33d plane_to_robot(std::cos(r), -std::sin(r) * m, spec.robot.dx, std::sin(r),
                                   std::cos(r) * m, spec.robot.dy, 0, 0, 1);
  cell.vision_to_robot = plane_to_robot * cell.plane_to_vision.inv();

  std::mt19937_64 rng(spec.seed);
  std::uniform_real_distribution<double> off(2, 20), dir(0, 2 * M_PI);
  std::normal_distribution<double> rn(0, spec.robot_noise), vn(0, spec.vision_noise);
  // Spread over the field as an integrator would: one point in each of
  // `points` cells of a grid (chosen at random when the grid has more),
  // anywhere within its cell.
  const int cols = static_cast<int>(std::ceil(std::sqrt(2.0 * spec.points)));
  const int rows = (spec.points + cols - 1) / cols;
  std::vector<int> grid(static_cast<size_t>(cols * rows));
  for (size_t i = 0; i < grid.size(); ++i) grid[i] = static_cast<int>(i);
  std::shuffle(grid.begin(), grid.end(), rng);
  std::uniform_real_distribution<double> within(0, 1);
  for (int i = 0; i < spec.points; ++i) {
    const int g = grid[static_cast<size_t>(i) % grid.size()];
    // Braces: the draws happen left to right with every compiler (the order
    // of a call's arguments is unspecified), so every build sees the same cells.
    const cv::Point2d plane{((g % cols) + within(rng)) / cols * spec.field_w - spec.field_w / 2,
                            ((g / cols) + within(rng)) / rows * spec.field_h - spec.field_h / 2};
    const cv::Point2d v = cell.toVision(plane);
    cv::Point2d robot = cell.truth(v) + cv::Point2d{rn(rng), rn(rng)};
    const bool bad = i < spec.outliers;
    if (bad) {
      const double d = off(rng), ang = dir(rng);
      robot += cv::Point2d(d * std::cos(ang), d * std::sin(ang));
    }
    cell.points.push_back({v + cv::Point2d{vn(rng), vn(rng)}, robot});
    cell.outlier.push_back(bad);
  }
  return cell;
}

}  // namespace picksight::test
