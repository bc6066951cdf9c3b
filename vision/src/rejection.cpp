// Region explanations: recognize()'s tests of a separated region, in its
// order, stopped at the first one a model fails.
#include "picksight/vision/rejection.hpp"

#include <algorithm>
#include <cmath>

#include "picksight/vision/blob_features.hpp"
#include "picksight/vision/boundary_model.hpp"
#include "picksight/vision/recognizer.hpp"

namespace picksight::vision {

const char* regionTestName(RegionTest test) {
  switch (test) {
    case RegionTest::kEdge:
      return "edge";
    case RegionTest::kHoles:
      return "holes";
    case RegionTest::kArea:
      return "area";
    case RegionTest::kHu:
      return "hu";
    case RegionTest::kMirror:
      return "mirror";
    case RegionTest::kVerify:
      return "verify";
    case RegionTest::kPasses:
      return "passes";
  }
  return "passes";
}

namespace {

// Best verified fraction over the rotation candidates, and its angle.
std::pair<double, double> bestScore(const PartModel& model, const std::vector<double>& turns,
                                    cv::Point2d centre, const EdgeDistance& edges, bool mirrored) {
  std::pair<double, double> best{-1.0, 0.0};
  for (double t : turns) {
    const double s = verifyScore(model.samples, centre, t, edges, model.edge_tolerance, mirrored);
    if (s > best.first) best = {s, t};
  }
  return best;
}

RegionExplanation explainOne(const Region& r, const PartModel& model, const HuArray& log_hu) {
  const BodyModel& body = model.body;
  RegionExplanation e;
  e.nearest = &model;
  if (r.touches_border) {
    e.test = RegionTest::kEdge;
    return e;
  }
  if (r.holes != body.holes) {
    e.test = RegionTest::kHoles;
    e.measured = r.holes;
    e.low = e.high = body.holes;
    return e;
  }
  if (std::abs(r.area - body.area) > body.area_tolerance * body.area) {
    e.test = RegionTest::kArea;
    e.measured = r.area;
    e.low = body.area * (1 - body.area_tolerance);
    e.high = body.area * (1 + body.area_tolerance);
    return e;
  }
  const double distance = huDistance(body, log_hu);
  if (distance > body.hu_tolerance) {
    // The 7th invariant changes sign in a mirror: a region whose mirror
    // image would pass is the mirror image of the part.
    HuArray mirrored = log_hu;
    mirrored[6] = -mirrored[6];
    const double mirror_distance = huDistance(body, mirrored);
    const bool mirror = !body.mirror_symmetric && mirror_distance <= body.hu_tolerance;
    e.test = mirror ? RegionTest::kMirror : RegionTest::kHu;
    e.measured = distance;
    e.low = e.high = body.hu_tolerance;
    return e;
  }
  if (!body.mirror_symmetric && body.hu_used[6] && (log_hu[6] >= 0) != (body.log_hu[6] >= 0)) {
    e.test = RegionTest::kMirror;
    e.measured = log_hu[6];
    e.low = e.high = body.log_hu[6];
    return e;
  }
  std::vector<std::vector<cv::Point>> contours{r.outer};
  contours.insert(contours.end(), r.hole_boundaries.begin(), r.hole_boundaries.end());
  const int m = static_cast<int>(std::ceil(model.edge_tolerance)) + 2;
  const EdgeDistance edges(
      contours, cv::Rect(r.bbox.x - m, r.bbox.y - m, r.bbox.width + 2 * m, r.bbox.height + 2 * m),
      2 * model.edge_tolerance);
  const auto turns = rotationCandidates(r, model);
  const auto direct = bestScore(model, turns, r.centroid, edges, false);
  if (direct.first * 100 < model.verify_percent) {
    e.test = RegionTest::kVerify;
    e.measured = std::max(0.0, direct.first) * 100;
    e.low = e.high = model.verify_percent;
    return e;
  }
  if (!body.mirror_symmetric) {
    // The mirror image's candidates turn the other way about the model's
    // phase: each direct one plus 2 phase / k.
    std::vector<double> mirror_turns = turns;
    const int k = model.orientation_order;
    if (k > 0)
      for (double& t : mirror_turns) t += 2 * model.orientation_phase_deg / k;
    const auto mirror = bestScore(model, mirror_turns, r.centroid, edges, true);
    if (showsMirrorImage(model, {r.centroid, direct.second, false},
                         {r.centroid, mirror.second, true}, edges)) {
      e.test = RegionTest::kMirror;
      e.measured = std::max(0.0, mirror.first) * 100;
      e.low = e.high = direct.first * 100;
      return e;
    }
  }
  e.measured = direct.first * 100;
  e.low = e.high = model.verify_percent;
  return e;
}
}  // namespace

RegionExplanation explainRegion(const Region& region, const std::vector<const PartModel*>& models) {
  RegionExplanation best;
  if (models.empty()) return best;
  const HuArray log_hu = logHu(huInvariants(region.moments));
  double best_area_gap = 0;
  for (const PartModel* model : models) {
    RegionExplanation e = explainOne(region, *model, log_hu);
    const double gap = std::abs(region.area - model->body.area) / std::max(model->body.area, 1.0);
    const bool nearer = !best.nearest || static_cast<int>(e.test) > static_cast<int>(best.test) ||
                        (e.test == best.test && gap < best_area_gap);
    if (!nearer) continue;
    best = e;
    best_area_gap = gap;
  }
  return best;
}

}  // namespace picksight::vision
