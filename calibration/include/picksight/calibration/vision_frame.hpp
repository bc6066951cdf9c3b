// The vision frame: where image pixels become millimetres on the work plane.
//
// Origin at the centre of sensor pixel (0, 0); x along the image rows (to
// the right), y against the image columns (up the image), so that, seen from
// above by a camera looking down, the frame is right-handed with Z up like a
// robot's. Angles are counter-clockwise as seen from above: an image angle
// (measured from x towards the downward image y) changes sign.
#pragma once

#include <optional>

#include <opencv2/core.hpp>

#include "picksight/calibration/camera_calibration.hpp"

namespace picksight::calibration {

class VisionFrame {
 public:
  VisionFrame() = default;  // 1 mm per pixel, no lens model
  VisionFrame(PixelScale scale, std::optional<LensModel> lens = std::nullopt);
  // No scale yet (1 unit per pixel, calibrated() false), but pixels are
  // undistorted by `lens` when set: a lens model is used wherever it exists.
  static VisionFrame pixels(std::optional<LensModel> lens);

  // Sensor pixels (undistorted first when a lens model is set) to mm.
  cv::Point2d toMm(cv::Point2d pixel) const;
  // mm back to (ideal, undistorted) sensor pixels.
  cv::Point2d toPixels(cv::Point2d mm) const;
  // An angle measured in image axes to the vision frame, and back; both in [0, 360).
  static double angleToVision(double image_deg);
  static double angleToImage(double vision_deg);
  // The same for a direction at a place (sensor pixel `at`; vision mm
  // `at_mm`): through the local scale on X and Y, lens and rectification,
  // which turn directions unevenly over the image of a tilted camera
  // (about 0.5 degree at the edge of a 1920 px image tilted 2 degrees).
  double directionToVision(double image_deg, cv::Point2d at) const;
  double directionToImage(double vision_deg, cv::Point2d at_mm) const;

  const PixelScale& scale() const { return scale_; }
  bool calibrated() const { return calibrated_; }

 private:
  PixelScale scale_{1.0, 1.0, 0.0};
  std::optional<LensModel> lens_;
  bool calibrated_ = false;
};

}  // namespace picksight::calibration
