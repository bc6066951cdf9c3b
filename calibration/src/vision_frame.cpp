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

cv::Point2d VisionFrame::toMm(cv::Point2d pixel) const {
  if (lens_) pixel = lens_->undistort({pixel}).front();
  return {pixel.x * scale_.mm_per_px_x, -pixel.y * scale_.mm_per_px_y};
}

cv::Point2d VisionFrame::toPixels(cv::Point2d mm) const {
  return {mm.x / scale_.mm_per_px_x, -mm.y / scale_.mm_per_px_y};
}

double VisionFrame::angleToVision(double image_deg) { return picksight::normalizeDeg(-image_deg); }

double VisionFrame::angleToImage(double vision_deg) { return angleToVision(vision_deg); }

}  // namespace picksight::calibration
