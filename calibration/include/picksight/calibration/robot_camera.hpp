// Robot-camera calibration for a camera fixed above a plane parallel to the
// robot's XY plane: the rigid transform (rotation about Z, translation) that
// takes a point from the vision frame (mm) to the robot frame (mm), from
// point pairs measured by touching a target with the robot.
//
// Handedness: a camera looking down sees the robot's plane from above, but
// image rows grow downwards, so image axes are a mirror image of the robot's.
// PickSight's vision frame flips the image y axis (x right, y up, seen from
// above), which makes it a rotation and translation away from any robot
// frame whose Z points up. The fit still checks the mirror case and reports
// it: a frame set up the other way round (camera under glass, a mirror in
// the optical path, or vision points taken in raw image axes) is detected
// from the points instead of producing a wrong transform.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/calibration/calibration_errors.hpp"
#include "picksight/common/result.hpp"

namespace picksight::calibration {

struct PointPair {
  cv::Point2d vision;  // mm, vision frame
  cv::Point2d robot;   // mm, robot frame
};

// robot = R(rz) * M * vision + (dx, dy), M = diag(1, -1) when mirrored.
struct RigidTransform {
  double dx = 0;
  double dy = 0;
  double rz_deg = 0;  // (-180, 180]
  bool mirrored = false;

  cv::Point2d apply(cv::Point2d vision) const;
  // Rotation of an angle measured in the vision frame, into the robot frame.
  double applyToAngleDeg(double vision_deg) const;
};

enum class Method { kBest, kGeometric, kLeastSquares };

struct Residual {
  double dx = 0;  // robot-frame error of the point: transform(vision) - robot
  double dy = 0;
  double distance = 0;
  bool inlier = true;
};

struct CalibrationResult {
  RigidTransform transform;
  Method method = Method::kLeastSquares;  // the estimator that produced it
  double rms = 0;                         // over inliers, mm
  std::vector<Residual> residuals;        // one per input point, same order
  int inliers = 0;
};

// Estimates the transform. kBest runs both estimators on the same inliers
// and keeps the lower RMS. Outliers (a mis-touched point) are found by least
// median of squares and left out of the fit; at least 3 inliers must remain.
Result<CalibrationResult> calibrate(const std::vector<PointPair>& points,
                                    Method method = Method::kBest);

const char* methodName(Method method);

}  // namespace picksight::calibration
