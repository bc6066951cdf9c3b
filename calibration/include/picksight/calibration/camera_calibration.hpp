// Camera calibration: the pixel scale in millimetres from a circular target
// of known radius, and optionally a full lens model
// (intrinsics and distortion) from chessboard views, used to undistort
// located points.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "picksight/common/result.hpp"

namespace picksight::calibration {

struct PixelScale {
  double mm_per_px_x = 0;
  double mm_per_px_y = 0;
  // How far the imaged circle's axes are from the image axes (degrees): a
  // large value means a tilted camera or a distorted lens, not a scale.
  double skew_deg = 0;
  // From a dot grid (CALCAM GRID): the homography that takes ideal
  // (undistorted) sensor pixels to the pixels of a camera looking straight
  // down, the perspective of a tilted camera taken out. It fixes the middle
  // of the dots and their local direction, so it departs from the identity
  // only by the tilt; the scale above then holds everywhere on the plane.
  std::optional<cv::Matx33d> rectify = std::nullopt;
};

// From the moments of the imaged target (a disc of `radius_mm`, seen as an
// ellipse when pixels are not square): for an ellipse of semi-axes a, b
// aligned with the image axes, mu20/m00 = a^2/4 and mu02/m00 = b^2/4.
// Sub-pixel (grey-level) moments give sub-pixel scales.
Result<PixelScale> scaleFromCircle(const cv::Moments& target, double radius_mm);

struct LensModel {
  cv::Size image_size;
  cv::Matx33d camera_matrix = cv::Matx33d::eye();
  std::vector<double> distortion;  // k1 k2 p1 p2 k3
  double rms_reprojection_px = 0;
  int views = 0;

  // Undistorts pixel positions into the ideal (distortion-free) image of the
  // same camera matrix.
  std::vector<cv::Point2d> undistort(const std::vector<cv::Point2d>& pixels) const;
};

struct ChessboardOptions {
  cv::Size inner_corners{9, 6};
  double square_mm = 25;
  bool fix_aspect_ratio = true;  // square pixels: fx = fy
};

// Calibrates from chessboard views; views where the board is not found are
// skipped (their names reported in `skipped`). Needs at least 3 good views.
Result<LensModel> calibrateChessboard(const std::vector<cv::Mat>& views,
                                      const ChessboardOptions& options,
                                      std::vector<int>* skipped = nullptr);

// Text form (OpenCV YAML) for storage; parse errors name the problem.
std::string lensModelToYaml(const LensModel& model);
Result<LensModel> lensModelFromYaml(const std::string& text);

}  // namespace picksight::calibration
