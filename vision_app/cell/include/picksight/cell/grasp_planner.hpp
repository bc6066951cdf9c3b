// From located parts to the poses a robot picks at: each part's pose in the
// vision frame, its first grasp style whose fingers cover no other part
// (see grasp/grasp.hpp), then the reply frame (robot once computed).
#pragma once

#include <string>
#include <vector>

#include "picksight/cell/vision_service.hpp"
#include "picksight/grasp/grasp.hpp"
#include "picksight/store/cell_calibration.hpp"
#include "picksight/store/model_library.hpp"

namespace picksight::cell {

struct CellPick {
  std::vector<grasp::Pose> poses;  // reply frame, in the order of the parts
  std::vector<size_t> parts;       // for each pose, its part in the outcome's parts
  std::vector<int> styles;         // for each pose, its grasp style (-1: the part's own pose)
  size_t skipped = 0;              // parts with no free grasp, not offered
  store::CoordinateFrame frame = store::CoordinateFrame::kVisionPixels;
};

// The scene's model of `type` (null: none, or a region's type -1).
const vision::PartModel* modelOf(const LocateScene& scene, int type);

// A located part's own pose in the vision frame: position in vision units,
// rotation counter-clockwise (a recognized part: from its trained pose, the
// turn nearest it, within half a symmetry period of the taught direction;
// a region: its axis direction, [0, 360)).
grasp::Pose partPoseInVisionFrame(const LocatedPart& part, const calibration::VisionFrame& vision);

// The reply-frame pose of the gripper holding `part` (its vision-frame pose
// `pose`) by `style`. For a recognized part the angle is the one within
// half a turn of the same grasp's angle on a part lying as taught (vision
// angle 0, at the vision origin) in the reply frame, that angle taken in
// (-180, 180]: the same part in the same place gives the same number, never
// one 360 apart. A region's (no model) is in [0, 360).
grasp::Pose replyPose(const LocatedPart& part, const grasp::Pose& pose,
                      const grasp::GraspStyle& style, const store::CellGeometry& geometry);

// The grasp poses of the parts of `outcome`. Obstacles are the scene's
// mask without the part's own pixels (for a part found touching others,
// without its placed model's footprint). A part of a type with no
// grasp styles is grasped at its own pose, checked against the fingers.
CellPick pickPoses(const LocateOutcome& outcome, const store::GraspMap& grasps,
                   const store::CellGeometry& geometry);

}  // namespace picksight::cell
