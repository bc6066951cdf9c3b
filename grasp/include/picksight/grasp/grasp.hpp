// Grasp selection with gripper clearance: each part model
// has grasp styles (where the gripper goes, in the part's own frame) and a
// gripper fingerprint (the finger rectangles in the gripper's frame). A grasp
// is offered only if its fingers cover no other part; the first free style
// in the model's order wins.
//
// Frames: part, gripper and fingers are in millimetres in the vision frame
// (picksight::calibration::VisionFrame: y up, angles counter-clockwise).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/calibration/vision_frame.hpp"

namespace picksight::grasp {

struct Pose {
  double x = 0;
  double y = 0;
  double rz_deg = 0;
};

// The gripper's pose relative to the part: offset and turn in the part frame.
struct GraspStyle {
  double x_mm = 0;
  double y_mm = 0;
  double rz_deg = 0;
};

// One finger's footprint: a rectangle centred at (x, y) in the gripper
// frame, sides along the gripper's axes.
struct Finger {
  double x_mm = 0;
  double y_mm = 0;
  double width_mm = 0;   // along the gripper x axis
  double height_mm = 0;  // along the gripper y axis
};

struct Gripper {
  std::vector<Finger> fingers;
};

// The gripper pose for a part pose and a style (both in the vision frame).
Pose gripperPose(const Pose& part, const GraspStyle& style);

// The fingers' corners in sensor pixels for a gripper pose.
std::vector<std::vector<cv::Point2d>> fingerPolygons(const Pose& gripper, const Gripper& fingers,
                                                     const calibration::VisionFrame& frame);

// Obstacles: a mask (non-zero = another part) and the affine map from sensor
// pixels to mask pixels (the frame's ROI and scale).
struct Obstacles {
  cv::Mat mask;                                  // CV_8UC1
  cv::Matx23d sensor_to_mask{1, 0, 0, 0, 1, 0};  // identity: mask in sensor pixels
};

// True when no finger covers an obstacle pixel. A finger reaching outside
// the mask covers what the camera cannot see, and counts as blocked: a
// robot must not be sent into the unknown.
bool fingersClear(const Pose& gripper, const Gripper& fingers,
                  const calibration::VisionFrame& frame, const Obstacles& obstacles);

// The fingers' corners of one grasp (fingerPolygons), in sensor pixels.
using FingerPolygons = std::vector<std::vector<cv::Point2d>>;

// True when none of the polygons covers an obstacle pixel (fingersClear
// for polygons already computed).
bool polygonsClear(const FingerPolygons& polygons, const Obstacles& obstacles);

// Index of the first grasp whose fingers' polygons are clear; nullopt when
// none is. For a caller that needs the polygons itself (to size the
// obstacle mask), so that they are computed once per grasp.
std::optional<size_t> firstClearGrasp(const std::vector<FingerPolygons>& grasps,
                                      const Obstacles& obstacles);

// Index of the first style whose grasp is clear; nullopt when none is (or
// when there are no styles). With no fingers every grasp is clear.
std::optional<size_t> firstClearGrasp(const Pose& part, const std::vector<GraspStyle>& styles,
                                      const Gripper& fingers, const calibration::VisionFrame& frame,
                                      const Obstacles& obstacles);

}  // namespace picksight::grasp
