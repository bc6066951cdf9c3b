// Pixel <-> vision-frame millimetre mapping.
#include "picksight/calibration/vision_frame.hpp"

#include <cmath>

#include "picksight/common/angles.hpp"

namespace picksight::calibration {

VisionFrame::VisionFrame(PixelScale scale, std::optional<LensModel> lens)
    : scale_(scale), lens_(std::move(lens)), calibrated_(true) {}

VisionFrame VisionFrame::pixels(std::optional<LensModel> lens) {
  VisionFrame f;
  f.lens_ = std::move(lens);
  return f;
}

namespace {
cv::Point2d project(const cv::Matx33d& h, cv::Point2d p) {
  const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1);
  return {q[0] / q[2], q[1] / q[2]};
}
}  // namespace

cv::Point2d VisionFrame::toMm(cv::Point2d pixel) const {
  if (lens_) pixel = lens_->undistort({pixel}).front();
  if (scale_.rectify) pixel = project(*scale_.rectify, pixel);
  return {pixel.x * scale_.mm_per_px_x, -pixel.y * scale_.mm_per_px_y};
}

cv::Point2d VisionFrame::toPixels(cv::Point2d mm) const {
  const cv::Point2d px(mm.x / scale_.mm_per_px_x, -mm.y / scale_.mm_per_px_y);
  return scale_.rectify ? project(scale_.rectify->inv(), px) : px;
}

double VisionFrame::angleToVision(double image_deg) { return picksight::normalizeDeg(-image_deg); }

double VisionFrame::angleToImage(double vision_deg) { return angleToVision(vision_deg); }

double VisionFrame::directionToVision(double image_deg, cv::Point2d at) const {
  const double a = image_deg / kDegPerRad;
  // Half a pixel each way: short enough to be local, long enough for the
  // lens's undistortion to resolve.
  const cv::Point2d step(0.5 * std::cos(a), 0.5 * std::sin(a));
  const cv::Point2d d = toMm(at + step) - toMm(at - step);
  return picksight::normalizeDeg(std::atan2(d.y, d.x) * kDegPerRad);
}

double VisionFrame::directionToImage(double vision_deg, cv::Point2d at_mm) const {
  const double a = vision_deg / kDegPerRad;
  const double len = 0.5 * std::sqrt(scale_.mm_per_px_x * scale_.mm_per_px_y);
  const cv::Point2d step(len * std::cos(a), len * std::sin(a));
  const cv::Point2d d = toPixels(at_mm + step) - toPixels(at_mm - step);
  return picksight::normalizeDeg(std::atan2(d.y, d.x) * kDegPerRad);
}

}  // namespace picksight::calibration
