// The simulated robot's hidden transform and the drawing of its calibration
// target: analytic discs in the robot plane, supersampled where a pixel
// straddles their edge.
#include "picksight/synthetic/simulated_robot.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "scene_internals.hpp"

namespace picksight::synthetic {
namespace {

using detail::kPi;

// Samples per pixel side where a pixel straddles a disc's edge: coverage to
// 1/1024 of a pixel, below the 8-bit image's own quantization.
constexpr int kSamplesPerSide = 32;

cv::Point2d apply(const cv::Matx33d& h, cv::Point2d p) {
  const double w = h(2, 0) * p.x + h(2, 1) * p.y + h(2, 2);
  return {(h(0, 0) * p.x + h(0, 1) * p.y + h(0, 2)) / w,
          (h(1, 0) * p.x + h(1, 1) * p.y + h(1, 2)) / w};
}

}  // namespace

const char* targetKindName(TargetKind kind) { return kind == TargetKind::kGrid ? "grid" : "disc"; }

RobotCameraModel::RobotCameraModel(const RobotCamera& camera, int width, int height)
    : camera_(camera) {
  const double a = camera.rz_deg * kPi / 180;
  const double c = std::cos(a);
  const double s = std::sin(a);
  // vision = R(-rz) * (robot - d); untilted pixel = (xv, -yv) / mm_per_px.
  const cv::Matx33d robot_to_vision(c, s, -(c * camera.dx_mm + s * camera.dy_mm),    //
                                    -s, c, -(-s * camera.dx_mm + c * camera.dy_mm),  //
                                    0, 0, 1);
  const double k = 1.0 / camera.mm_per_px;
  const cv::Matx33d vision_to_pixel(k, 0, 0, 0, -k, 0, 0, 0, 1);
  const double cx = 0.5 * (width - 1);
  const double cy = 0.5 * (height - 1);
  const double f = width;
  const cv::Matx33d to_centre(1, 0, -cx, 0, 1, -cy, 0, 0, 1);
  const cv::Matx33d tilt(1, 0, 0, 0, 1, 0, std::tan(camera.tilt_x_deg * kPi / 180) / f,
                         std::tan(camera.tilt_y_deg * kPi / 180) / f, 1);
  const cv::Matx33d from_centre(1, 0, cx, 0, 1, cy, 0, 0, 1);
  robot_to_image_ = from_centre * tilt * to_centre * vision_to_pixel * robot_to_vision;
  image_to_robot_ = robot_to_image_.inv();
}

cv::Point2d RobotCameraModel::toImage(cv::Point2d robot_mm) const {
  return apply(robot_to_image_, robot_mm);
}

cv::Point2d RobotCameraModel::toRobot(cv::Point2d image_px) const {
  return apply(image_to_robot_, image_px);
}

std::vector<cv::Point2d> targetDots(const CalibrationTarget& target, cv::Point2d at_mm) {
  if (target.kind == TargetKind::kDisc) return {at_mm};
  std::vector<cv::Point2d> dots;
  dots.reserve(static_cast<size_t>(target.rows) * static_cast<size_t>(target.cols));
  for (int r = 0; r < target.rows; ++r) {
    for (int c = 0; c < target.cols; ++c) {
      dots.emplace_back(at_mm.x + (c - 0.5 * (target.cols - 1)) * target.pitch_mm,
                        at_mm.y + (r - 0.5 * (target.rows - 1)) * target.pitch_mm);
    }
  }
  return dots;
}

std::vector<TargetDotTruth> drawTarget(cv::Mat& image, const cv::Mat& light,
                                       const RobotCameraModel& model,
                                       const CalibrationTarget& target, cv::Point2d at_mm,
                                       double level) {
  CV_Assert(image.type() == CV_32FC1);
  std::vector<TargetDotTruth> truth;
  const double r = target.radius_mm;
  const double r2 = r * r;
  for (const cv::Point2d& centre : targetDots(target, at_mm)) {
    TargetDotTruth dot;
    dot.robot_mm = centre;
    dot.image_px = model.toImage(centre);
    // The disc's image is convex: its bounding box from points on its edge.
    double min_x = 1e300, max_x = -1e300, min_y = 1e300, max_y = -1e300;
    constexpr int kEdgePoints = 256;
    for (int i = 0; i < kEdgePoints; ++i) {
      const double t = 2 * kPi * i / kEdgePoints;
      const cv::Point2d p = model.toImage(centre + r * cv::Point2d(std::cos(t), std::sin(t)));
      min_x = std::min(min_x, p.x);
      max_x = std::max(max_x, p.x);
      min_y = std::min(min_y, p.y);
      max_y = std::max(max_y, p.y);
    }
    const int x0 = std::max(0, static_cast<int>(std::floor(min_x)) - 2);
    const int x1 = std::min(image.cols - 1, static_cast<int>(std::ceil(max_x)) + 2);
    const int y0 = std::max(0, static_cast<int>(std::floor(min_y)) - 2);
    const int y1 = std::min(image.rows - 1, static_cast<int>(std::ceil(max_y)) + 2);
    for (int y = y0; y <= y1; ++y) {
      float* row = image.ptr<float>(y);
      const float* lit = light.empty() ? nullptr : light.ptr<float>(y);
      for (int x = x0; x <= x1; ++x) {
        // The pixel's footprint in the robot plane is a convex quadrilateral:
        // wholly inside or outside the disc when its centre is farther than
        // the footprint's reach from the disc's edge.
        const cv::Point2d mid = model.toRobot({double(x), double(y)});
        double reach = 0;
        const std::array<cv::Point2d, 4> corners = {
            cv::Point2d(x - 0.5, y - 0.5), cv::Point2d(x + 0.5, y - 0.5),
            cv::Point2d(x - 0.5, y + 0.5), cv::Point2d(x + 0.5, y + 0.5)};
        for (const cv::Point2d& c : corners) {
          reach = std::max(reach, cv::norm(model.toRobot(c) - mid));
        }
        const double d = cv::norm(mid - centre);
        double coverage = 0;
        if (d + reach <= r) {
          coverage = 1;
        } else if (d - reach < r) {
          int inside = 0;
          for (int j = 0; j < kSamplesPerSide; ++j) {
            const double sy = y - 0.5 + (j + 0.5) / kSamplesPerSide;
            for (int i = 0; i < kSamplesPerSide; ++i) {
              const double sx = x - 0.5 + (i + 0.5) / kSamplesPerSide;
              const cv::Point2d q = model.toRobot({sx, sy}) - centre;
              inside += q.x * q.x + q.y * q.y <= r2 ? 1 : 0;
            }
          }
          coverage = static_cast<double>(inside) / (kSamplesPerSide * kSamplesPerSide);
        }
        if (coverage <= 0) continue;
        dot.area_px += coverage;
        const double l = lit ? lit[x] : 1.0;
        // Over whatever lies below (background or a part), as the robot holds
        // the target above the scene.
        row[x] = static_cast<float>(row[x] + coverage * (level * l - row[x]));
      }
    }
    truth.push_back(dot);
  }
  return truth;
}

}  // namespace picksight::synthetic
