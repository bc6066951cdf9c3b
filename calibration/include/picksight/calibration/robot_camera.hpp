// Robot-camera calibration for a camera fixed above a plane (nearly)
// parallel to the robot's XY plane: the transform that takes a point from
// the vision frame (mm) to the robot frame (mm), from point pairs measured
// by touching a target with the robot. Three models, from the stiffest:
// rigid (rotation about Z and translation: the camera scale is trusted),
// similarity (plus one scale taken from the robot's own points: corrects a
// camera scale a fraction of a percent off), homography (the full
// plane-to-plane projection: a camera tilted by a degree or two).
//
// Handedness: a camera looking down sees the robot's plane from above, but
// image rows grow downwards, so image axes are a mirror image of the robot's.
// PickSight's vision frame flips the image y axis (x right, y up, seen from
// above), which makes it a rotation and translation away from any robot
// frame whose Z points up. The fits still check the mirror case and report
// it: a frame set up the other way round (camera under glass, a mirror in
// the optical path, or vision points taken in raw image axes) is detected
// from the points instead of producing a wrong transform.
//
// Threading: pure functions and values.
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

enum class TransformModel { kRigid, kSimilarity, kHomography, kTilt };

// Any of the models as a 3x3 matrix on homogeneous points, with its
// reading at the vision origin: for rigid and similarity transforms these
// are their exact parameters; for a tilt or a homography the local ones there.
struct PlaneTransform {
  TransformModel model = TransformModel::kRigid;
  cv::Matx33d matrix = cv::Matx33d::eye();  // robot ~ matrix * (vision, 1)
  double dx = 0;                            // robot position of the vision origin
  double dy = 0;
  double rz_deg = 0;  // direction of the vision x axis in the robot frame, (-180, 180]
  double scale = 1;   // robot mm per vision mm
  bool mirrored = false;

  static PlaneTransform rigid(const RigidTransform& t);
  static PlaneTransform similarity(const RigidTransform& t, double scale);
  // Fails unless `h` is finite and invertible.
  static Result<PlaneTransform> homography(const cv::Matx33d& h);

  cv::Point2d apply(cv::Point2d vision) const;
  // An angle measured in the vision frame at vision point `at`, into the
  // robot frame (a homography turns directions differently across the plane).
  double applyToAngleDeg(double vision_deg, cv::Point2d at = {0, 0}) const;
};

enum class Method { kBest, kGeometric, kLeastSquares, kSimilarity, kHomography, kTilt };

struct Residual {
  double dx = 0;  // robot-frame error of the point: transform(vision) - robot
  double dy = 0;
  double distance = 0;
  bool inlier = true;
};

struct CalibrationResult {
  PlaneTransform transform;
  Method method = Method::kLeastSquares;  // the estimator that produced it
  double rms = 0;                         // over inliers, mm
  std::vector<Residual> residuals;        // one per input point, same order
  int inliers = 0;
  // Expected error at a point not fitted (mm): the RMS of each inlier
  // predicted by the fit of the others (cross-validation). What kBest
  // compares between the two rigid estimators.
  double predicted_error = 0;
};

// Least fit points for each method: rigid 3, similarity 3, tilt 4, homography 6.
int minimumPoints(Method method);

// Estimates the transform. Outliers (a mis-touched point) are found by
// least median of squares over random minimal samples (a fixed number, a
// fixed seed: the same points always give the same result, in time linear
// in the number of points) and left out of the fit.
//
// kBest finds the outliers with the most general model the points allow
// (the homography from 8 points, the tilt from 6, else the similarity) and
// fits the models to the same inliers, the most general being the
// homography from 8 inliers, else the tilt from 6, else the similarity.
// From the most general down, a stiffer model replaces the one kept when it
// fits as well up to the noise: an F-test on the rise of the residual sum
// of squares against the kept model's own noise estimate, at a 0.1 %
// false-alarm rate whatever the noise level and the number of points. Of
// the two rigid estimators, the one that better predicts points left out
// of its fit.
Result<CalibrationResult> calibrate(const std::vector<PointPair>& points,
                                    Method method = Method::kBest);

// "best", "geometric", "lsq", "similarity", "tilt", "homography"
const char* methodName(Method method);
const char* modelName(TransformModel model);  // "rigid", "similarity", "tilt", "homography"

}  // namespace picksight::calibration
