// Calibration targets measured to a hundredth of a pixel on their edges: a
// disc (centre and radii) and a grid of dots of known pitch (scale on X and
// on Y), on blurred, noisy, unevenly lit grey images.
//
// Why edges and not moments: a region's moments depend on where the
// threshold cuts the blurred edge (a dark threshold makes a bright disc
// larger), and grey-weighted moments on the background level and the
// illumination under the target. The edge position is where the grey level
// changes fastest, which neither moves.
//
// Threading: pure functions.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "picksight/calibration/calibration_errors.hpp"
#include "picksight/calibration/camera_calibration.hpp"
#include "picksight/common/result.hpp"

namespace picksight::calibration {

// An imaged disc: an ellipse when the pixels are not square (or the camera
// is tilted), in the pixels of the image it was measured on.
struct DiscMeasurement {
  cv::Point2d centre;
  double radius_x = 0;  // half the ellipse's extent along image x
  double radius_y = 0;  // along image y
  double major = 0;     // semi-axes
  double minor = 0;
  double axis_deg = 0;    // direction of the major axis, image axes
  int edge_points = 0;    // edge points the ellipse was fitted to
  double edge_rms = 0;    // their scatter about it (noise, dust), pixels
  double edge_width = 0;  // standard deviation of the edge's blur, pixels
};

// Measures the disc around `centre_guess` of about `radius_guess` pixels
// (a thresholded region's centroid and equivalent radius are good enough):
// grey levels are sampled along rays from the centre, each ray's edge is the
// centroid of its gradient (weighted to cancel the inward shift blur gives a
// curved edge), and an ellipse is fitted to the edge points; three rounds,
// each centred on the last. Bright on dark or dark on bright.
// CalibrationErrc::kBadTarget when no clear edge is found all round.
Result<DiscMeasurement> measureDisc(const cv::Mat& grey, cv::Point2d centre_guess,
                                    double radius_guess);

// Millimetres per pixel from a measured disc of `radius_mm`.
Result<PixelScale> scaleFromDisc(const DiscMeasurement& disc, double radius_mm);

struct DotGridMeasurement {
  PixelScale scale;
  int dots = 0;
  int rows = 0;             // along the grid's second direction
  int cols = 0;             // along its first (nearest image x)
  double grid_rms_px = 0;   // dot centres about the fitted grid
  double rotation_deg = 0;  // the grid's first direction, image axes
  std::vector<cv::Point2d> centres;
  std::vector<cv::Point2i> indices;  // each centre's place in the grid (steps)
};

// Measures a regular grid of dots `pitch_mm` apart (at least 2 x 2):
// every dot's centre by measureDisc, then the grid that fits them best. The
// grid's two step vectors in pixels give millimetres per pixel on X and on Y
// separately, whatever the grid's rotation.
Result<DotGridMeasurement> measureDotGrid(const cv::Mat& grey, double pitch_mm);

}  // namespace picksight::calibration
