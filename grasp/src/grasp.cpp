// Grasp clearance by rasterizing the finger footprints over the obstacles.
#include "picksight/grasp/grasp.hpp"

#include <opencv2/imgproc.hpp>

#include <cmath>

#include "picksight/common/angles.hpp"

namespace picksight::grasp {
namespace {
constexpr int kShift = 4;  // sub-pixel bits for fillPoly

cv::Point2d rotate(cv::Point2d p, double deg) {
  const double c = std::cos(deg * kRadPerDeg), s = std::sin(deg * kRadPerDeg);
  return {c * p.x - s * p.y, s * p.x + c * p.y};
}
}  // namespace

Pose gripperPose(const Pose& part, const GraspStyle& style) {
  const cv::Point2d offset = rotate({style.x_mm, style.y_mm}, part.rz_deg);
  return {part.x + offset.x, part.y + offset.y, normalizeDeg(part.rz_deg + style.rz_deg)};
}

std::vector<std::vector<cv::Point2d>> fingerPolygons(const Pose& gripper, const Gripper& fingers,
                                                     const calibration::VisionFrame& frame) {
  std::vector<std::vector<cv::Point2d>> polygons;
  for (const auto& f : fingers.fingers) {
    std::vector<cv::Point2d> poly;
    for (auto [sx, sy] : {std::pair{-1, -1}, std::pair{1, -1}, std::pair{1, 1}, std::pair{-1, 1}}) {
      const cv::Point2d corner(f.x_mm + sx * f.width_mm / 2, f.y_mm + sy * f.height_mm / 2);
      const cv::Point2d mm = cv::Point2d(gripper.x, gripper.y) + rotate(corner, gripper.rz_deg);
      poly.push_back(frame.toPixels(mm));
    }
    polygons.push_back(poly);
  }
  return polygons;
}

bool fingersClear(const Pose& gripper, const Gripper& fingers,
                  const calibration::VisionFrame& frame, const Obstacles& obstacles) {
  return polygonsClear(fingerPolygons(gripper, fingers, frame), obstacles);
}

bool polygonsClear(const FingerPolygons& polygons, const Obstacles& obstacles) {
  const cv::Rect image(0, 0, obstacles.mask.cols, obstacles.mask.rows);
  for (const auto& poly : polygons) {
    std::vector<cv::Point> fixed;
    std::vector<cv::Point2d> in_mask;
    for (const auto& p : poly) {
      const cv::Matx23d& a = obstacles.sensor_to_mask;
      const cv::Point2d m(a(0, 0) * p.x + a(0, 1) * p.y + a(0, 2),
                          a(1, 0) * p.x + a(1, 1) * p.y + a(1, 2));
      in_mask.push_back(m);
      fixed.emplace_back(static_cast<int>(std::lround(m.x * (1 << kShift))),
                         static_cast<int>(std::lround(m.y * (1 << kShift))));
    }
    std::vector<cv::Point2f> as_float(in_mask.begin(), in_mask.end());
    const cv::Rect box = cv::boundingRect(as_float);
    // Pixel centres at integers: a finger edge at -0.5 is still inside.
    if (box.x < -1 || box.y < -1 || box.br().x > image.width + 1 || box.br().y > image.height + 1)
      return false;
    const cv::Rect clipped = (box + cv::Size(2, 2)) & image;
    if (clipped.empty()) return false;
    cv::Mat footprint(clipped.size(), CV_8UC1, cv::Scalar(0));
    for (auto& p : fixed) p -= cv::Point(clipped.x << kShift, clipped.y << kShift);
    cv::fillPoly(footprint, std::vector<std::vector<cv::Point>>{fixed}, cv::Scalar(255), cv::LINE_8,
                 kShift);
    if (cv::countNonZero(footprint & obstacles.mask(clipped)) > 0) return false;
  }
  return true;
}

std::optional<size_t> firstClearGrasp(const std::vector<FingerPolygons>& grasps,
                                      const Obstacles& obstacles) {
  for (size_t i = 0; i < grasps.size(); ++i) {
    if (polygonsClear(grasps[i], obstacles)) return i;
  }
  return std::nullopt;
}

std::optional<size_t> firstClearGrasp(const Pose& part, const std::vector<GraspStyle>& styles,
                                      const Gripper& fingers, const calibration::VisionFrame& frame,
                                      const Obstacles& obstacles) {
  std::vector<FingerPolygons> grasps;
  for (const auto& style : styles)
    grasps.push_back(fingerPolygons(gripperPose(part, style), fingers, frame));
  return firstClearGrasp(grasps, obstacles);
}

}  // namespace picksight::grasp
