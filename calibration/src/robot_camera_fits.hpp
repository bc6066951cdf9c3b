// The robot-camera estimators behind calibrate(): least-squares fits of
// each model, the paper's geometric method, and least median of squares
// over random minimal samples. Private to the calibration library.
#pragma once

#include <optional>
#include <vector>

#include "picksight/calibration/robot_camera.hpp"

namespace picksight::calibration::fits {

// Points closer together than this (mm) along a spread's minor axis, or a
// triangle's height, are taken as lying on one line.
constexpr double kMinSpreadMm = 1.0;

// Least squares over all of `pts` (at least 2; 4 for the homography).
RigidTransform rigid(const std::vector<PointPair>& pts, bool mirrored);
PlaneTransform similarity(const std::vector<PointPair>& pts, bool mirrored);
// Normalized direct linear transform; nullopt when the points are degenerate.
std::optional<PlaneTransform> homography(const std::vector<PointPair>& pts);
// The similarity followed by a perspective division (a slightly tilted
// camera, 6 parameters), about the points' centroids; at least 3 points;
// nullopt when they are degenerate.
std::optional<PlaneTransform> tilt(const std::vector<PointPair>& pts, bool mirrored);

// The paper's geometric method on all of `pts` (rigid). At most a fixed
// number of point pairs take part, so the time stays bounded.
RigidTransform geometric(const std::vector<PointPair>& pts, bool mirrored, double cluster_radius);

// Least squares of `model` (handedness given for rigid and similarity).
std::optional<PlaneTransform> fitModel(const std::vector<PointPair>& pts, TransformModel model,
                                       bool mirrored);

struct RobustFit {
  PlaneTransform transform;  // refitted on the inliers
  std::vector<bool> inliers;
};

// Least median of squares over minimal samples of `model` (every sample
// when there are few, else a fixed number drawn with a fixed seed), then the
// inliers within 2.5 robust standard deviations (never under 0.1 mm) of the
// refit on the core. nullopt when no sample gives a transform.
std::optional<RobustFit> robustFit(const std::vector<PointPair>& pts, TransformModel model);

std::vector<PointPair> select(const std::vector<PointPair>& pts, const std::vector<bool>& use);

}  // namespace picksight::calibration::fits
