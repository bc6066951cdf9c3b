// Pixel <-> vision-frame millimetre mapping.
#include "picksight/calibration/vision_frame.hpp"

#include <cmath>

namespace picksight::calibration {

VisionFrame::VisionFrame(PixelScale scale, std::optional<LensModel> lens)
    : scale_(scale), lens_(std::move(lens)), calibrated_(true) {}

cv::Point2d VisionFrame::toMm(cv::Point2d pixel) const {
  if (lens_) pixel = lens_->undistort({pixel}).front();
  return {pixel.x * scale_.mm_per_px_x, -pixel.y * scale_.mm_per_px_y};
}

cv::Point2d VisionFrame::toPixels(cv::Point2d mm) const {
  return {mm.x / scale_.mm_per_px_x, -mm.y / scale_.mm_per_px_y};
}

double VisionFrame::angleToVision(double image_deg) {
  double d = std::fmod(-image_deg, 360.0);
  if (d < 0) d += 360.0;
  return d >= 360.0 ? 0.0 : d;
}

double VisionFrame::angleToImage(double vision_deg) { return angleToVision(vision_deg); }

}  // namespace picksight::calibration
