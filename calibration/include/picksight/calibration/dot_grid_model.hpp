// The camera seen through a grid of dots: besides the scale, the tilt of a
// camera that does not look straight down (a plane-to-image homography) and,
// when the dots cover the sensor, the lens's radial distortion, so that the
// vision frame is exact millimetres on the plane everywhere and the
// robot-camera fit needs only a rigid or similarity transform.
#pragma once

#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/calibration/camera_calibration.hpp"
#include "picksight/common/result.hpp"

namespace picksight::calibration {

struct DotGridModel {
  PixelScale scale;               // square on the plane, with `rectify`
  std::optional<LensModel> lens;  // radial distortion, when it was fitted
  double rms_px = 0;              // dot centres about the fitted model
  // Largest move the rectification makes at a dot (sensor px): the size of
  // the tilt's effect over the grid (0 for a camera looking straight down).
  double perspective_px = 0;
};

// Fits the grid `pitch_mm` apart seen at `centres` (sensor pixels, each at
// its grid place `indices`): a homography from 9 dots in at least 3 rows
// and 3 columns, else an affine scale alone (no rectification). `lens`: a
// lens model to trust (the centres are undistorted by it first). Without
// one, and with `sensor` (the whole sensor's size, so its middle is the
// centre of distortion), radial distortion (k1, k2) is fitted too when the
// dots reach at least 60 % of the way from the middle to a corner: a fit
// over the middle alone would extrapolate to the corners.
Result<DotGridModel> fitDotGrid(const std::vector<cv::Point2d>& centres,
                                const std::vector<cv::Point2i>& indices, double pitch_mm,
                                const std::optional<LensModel>& lens,
                                std::optional<cv::Size> sensor);

}  // namespace picksight::calibration
