// Grasp selection over a located scene, with local obstacle masks so that a
// frame with many parts costs a few small copies, not a full mask per part.
#include "picksight/cell/grasp_planner.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

#include "picksight/common/angles.hpp"

namespace picksight::cell {

using store::CellGeometry;
using store::GraspMap;

namespace {
// Footprint margin (frame pixels) around a placed model: covers its
// anti-aliased edge and a small pose error, so that a part never blocks
// its own grasp.
constexpr int kFootprintMargin = 3;

cv::Point2d apply(const cv::Matx23d& a, cv::Point2d p) {
  return {a(0, 0) * p.x + a(0, 1) * p.y + a(0, 2), a(1, 0) * p.x + a(1, 1) * p.y + a(1, 2)};
}

// The outer boundary of `model` placed at a part's pose, in frame pixels.
std::vector<std::vector<cv::Point>> placedFootprint(const vision::PartModel& model,
                                                    cv::Point2d centre, double image_deg,
                                                    cv::Point offset) {
  const double a = image_deg * M_PI / 180.0;
  const double c = std::cos(a), s = std::sin(a);
  std::vector<std::vector<cv::Point>> polys;
  for (const auto& loop : model.loops) {
    if (loop.hole) continue;
    std::vector<cv::Point> poly;
    for (const auto& prim : loop.primitives) {
      const int steps = prim.kind == vision::PrimitiveKind::kLine
                            ? 1
                            : std::clamp(static_cast<int>(prim.length() / 2.0), 2, 256);
      for (int k = 0; k < steps; ++k) {
        const cv::Point2d p = prim.pointAt(static_cast<double>(k) / steps);
        const cv::Point2d q(centre.x + c * p.x - s * p.y, centre.y + s * p.x + c * p.y);
        poly.emplace_back(static_cast<int>(std::lround(q.x)) - offset.x,
                          static_cast<int>(std::lround(q.y)) - offset.y);
      }
    }
    if (poly.size() >= 3) polys.push_back(std::move(poly));
  }
  return polys;
}

// Obstacles around one part: the mask over the box the fingers can reach,
// without the part's own pixels.
grasp::Obstacles obstaclesFor(const LocatedPart& part, const LocateScene& scene,
                              const std::vector<grasp::FingerPolygons>& grasps) {
  const cv::Matx23d to_frame = scene.mapping.sensorToFrame();
  std::vector<cv::Point2f> corners;
  for (const auto& polygons : grasps)
    for (const auto& poly : polygons)
      for (const auto& p : poly) corners.emplace_back(apply(to_frame, p));
  const cv::Rect image(0, 0, scene.mask.cols, scene.mask.rows);
  cv::Rect box = cv::boundingRect(corners);
  box = cv::Rect(box.x - 2, box.y - 2, box.width + 4, box.height + 4) & image;
  if (box.empty()) box = cv::Rect(0, 0, 1, 1) & image;  // fingers outside: blocked anyway

  grasp::Obstacles obstacles;
  obstacles.mask = scene.mask(box).clone();
  obstacles.sensor_to_mask = to_frame;
  obstacles.sensor_to_mask(0, 2) -= box.x;
  obstacles.sensor_to_mask(1, 2) -= box.y;
  if (part.region < 0 || static_cast<size_t>(part.region) >= scene.regions.size()) return obstacles;

  const vision::Region& region = scene.regions[static_cast<size_t>(part.region)];
  cv::Mat own(box.size(), CV_8UC1, cv::Scalar(0));
  const std::vector<std::vector<cv::Point>> outer{region.outer};
  cv::drawContours(own, outer, 0, cv::Scalar(255), cv::FILLED, cv::LINE_8, cv::noArray(), 0,
                   -box.tl());
  // A part recognized in a region of its own is that region; one found in a
  // blob shared with other parts (vision decided: LocatedPart::touching)
  // owns only its placed footprint.
  const vision::PartModel* model = modelOf(scene, part.type);
  if (model && part.touching) {
    const cv::Point2d centre = apply(to_frame, {part.x, part.y});
    const auto polys = placedFootprint(*model, centre, part.angle_deg, box.tl());
    cv::Mat footprint(box.size(), CV_8UC1, cv::Scalar(0));
    cv::fillPoly(footprint, polys, cv::Scalar(255));
    cv::polylines(footprint, polys, true, cv::Scalar(255), 2 * kFootprintMargin + 1);
    own &= footprint;
  }
  obstacles.mask.setTo(0, own);
  return obstacles;
}
}  // namespace

const vision::PartModel* modelOf(const LocateScene& scene, int type) {
  if (!scene.models || type < 0) return nullptr;
  for (const auto& m : *scene.models)
    if (m.type == type) return &m;
  return nullptr;
}

grasp::Pose partPoseInVisionFrame(const LocatedPart& part, const calibration::VisionFrame& vision) {
  const cv::Point2d at = vision.toMm({part.x, part.y});
  // The vision frame flips y, so an image rotation turns the other way; a
  // tilted camera's rectification turns directions a little more, locally.
  const double direction = vision.directionToVision(part.angle_deg, {part.x, part.y});
  if (part.type < 0) return {at.x, at.y, direction};
  // The turn nearest the taught pose, as the vision library chose it in
  // the image (reportedTurnDeg), kept so here: wrapped into [0, S) instead,
  // a bar lying at its taught angle (image -0.01 -> vision 0.01, image 0.01
  // -> vision -0.01 -> 179.99) would flip half a turn between frames, and
  // its grasp with it. The taught direction here is ~0 (the y flip keeps
  // it), a tilted camera's rectification turning it a little.
  const double taught = signedDeg(vision.directionToVision(0, {part.x, part.y}));
  return {at.x, at.y, nearestTurnDeg(direction, taught, part.symmetry_deg)};
}

grasp::Pose replyPose(const LocatedPart& part, const grasp::Pose& pose,
                      const grasp::GraspStyle& style, const CellGeometry& geometry) {
  grasp::Pose reply = geometry.toReply(grasp::gripperPose(pose, style));
  if (part.type < 0) return reply;
  // The frames' conversions wrap angles into [0, 360): a part near its
  // taught angle whose grasp points along the robot's x axis would read
  // 0.01 one LOCATE and 359.99 the next. The reply is the turn within half
  // a turn of this grasp's angle on a part lying as taught (vision angle
  // 0), taken at the vision origin so that it is one number per
  // calibration and style, never a wrap of its own.
  const double taught =
      signedDeg(geometry.toReply(grasp::gripperPose({0.0, 0.0, 0.0}, style)).rz_deg);
  reply.rz_deg = nearestTurnDeg(reply.rz_deg, taught, 360.0);
  return reply;
}

CellPick pickPoses(const LocateOutcome& outcome, const GraspMap& grasps,
                   const CellGeometry& geometry) {
  static const std::vector<grasp::GraspStyle> kOwnPose{grasp::GraspStyle{}};
  CellPick pick;
  pick.frame = geometry.frame();
  for (size_t index = 0; index < outcome.parts.size(); ++index) {
    const LocatedPart& part = outcome.parts[index];
    const grasp::Pose pose = partPoseInVisionFrame(part, geometry.vision);
    const auto setup = part.type >= 0 ? grasps.find(part.type) : grasps.end();
    const bool has_setup = setup != grasps.end();
    const auto& styles =
        has_setup && !setup->second.styles.empty() ? setup->second.styles : kOwnPose;
    if (!has_setup || setup->second.gripper.fingers.empty()) {
      pick.poses.push_back(replyPose(part, pose, styles.front(), geometry));
      pick.parts.push_back(index);
      pick.styles.push_back(&styles == &kOwnPose ? -1 : 0);
      continue;
    }
    // Each style's fingers, once: they size the obstacle mask and are
    // tested against it.
    std::vector<grasp::FingerPolygons> reach;
    for (const auto& style : styles) {
      reach.push_back(grasp::fingerPolygons(grasp::gripperPose(pose, style), setup->second.gripper,
                                            geometry.vision));
    }
    const grasp::Obstacles obstacles = obstaclesFor(part, outcome.scene, reach);
    const auto chosen = grasp::firstClearGrasp(reach, obstacles);
    if (!chosen) {
      ++pick.skipped;
      continue;
    }
    pick.poses.push_back(replyPose(part, pose, styles[*chosen], geometry));
    pick.parts.push_back(index);
    pick.styles.push_back(&styles == &kOwnPose ? -1 : static_cast<int>(*chosen));
  }
  return pick;
}

}  // namespace picksight::cell
