// A simulated robot for the synthetic camera: the hidden robot-camera
// transform and the calibration target (a disc or a grid of dots) the robot
// holds at robot coordinates, drawn with exact anti-aliasing so that the
// truth a calibration is checked against is exact.
//
// The transform is stated in the terms of the robot protocol
// (docs/PROTOCOL.md): a sensor pixel (u, v) is the vision point
// (u * mm_per_px, -v * mm_per_px) mm (y up the image), and
//   robot = R(rz_deg) * vision + (dx_mm, dy_mm).
// A tilted camera adds a perspective about the image centre: a camera turned
// by tilt_x_deg about the image's vertical axis and tilt_y_deg about its
// horizontal axis, with a focal length of `width` pixels, sees the untilted
// image point (cx + a, cy + b) at (cx + a / w, cy + b / w) with
//   w = 1 + (a tan(tilt_x) + b tan(tilt_y)) / width,
// so the scale at the image centre stays mm_per_px.
//
// Threading: plain values; no shared state.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace picksight::synthetic {

struct RobotCamera {
  double mm_per_px = 0.25;
  double rz_deg = 0;  // robot = R(rz) * vision + (dx, dy)
  double dx_mm = 0;
  double dy_mm = 0;
  double tilt_x_deg = 0;
  double tilt_y_deg = 0;
};

enum class TargetKind { kDisc, kGrid };

// A dark disc of radius_mm centred on the robot's point, or a grid of
// rows x cols such discs pitch_mm apart along the robot's X and Y axes,
// centred on the robot's point.
struct CalibrationTarget {
  TargetKind kind = TargetKind::kDisc;
  double radius_mm = 5;
  int rows = 5;
  int cols = 7;
  double pitch_mm = 20;
};

// "disc" or "grid".
const char* targetKindName(TargetKind kind);

// The transform of `camera` for an image of `width` x `height` pixels.
class RobotCameraModel {
 public:
  RobotCameraModel(const RobotCamera& camera, int width, int height);

  const RobotCamera& camera() const { return camera_; }
  // Sensor pixel of a robot point (mm), and back.
  cv::Point2d toImage(cv::Point2d robot_mm) const;
  cv::Point2d toRobot(cv::Point2d image_px) const;
  // The same as a homography: image ~ H * (X, Y, 1).
  cv::Matx33d robotToImage() const { return robot_to_image_; }

 private:
  RobotCamera camera_;
  cv::Matx33d robot_to_image_;
  cv::Matx33d image_to_robot_;
};

// Where one dot of a target lies: its centre in robot mm, the image of that
// centre, and the area its drawn pixels cover (sum of coverage).
struct TargetDotTruth {
  cv::Point2d robot_mm;
  cv::Point2d image_px;
  double area_px = 0;
};

// The dot centres (robot mm) of `target` held at `at_mm`.
std::vector<cv::Point2d> targetDots(const CalibrationTarget& target, cv::Point2d at_mm);

// Draws the target's dots into `image` (CV_32F) with their exact coverage as
// `model` images them, over what is there: pixel += coverage * (level * light
// - pixel). Edge pixels are supersampled (32 x 32 samples), the rest are
// wholly in or out.
std::vector<TargetDotTruth> drawTarget(cv::Mat& image, const cv::Mat& light,
                                       const RobotCameraModel& model,
                                       const CalibrationTarget& target, cv::Point2d at_mm,
                                       double level);

}  // namespace picksight::synthetic
