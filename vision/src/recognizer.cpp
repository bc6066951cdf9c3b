// Recognition: separated parts through body gates (holes, area, Hu distance),
// rotation candidates from complex moments
// and the boundary model verified at each candidate pose; blobs that match
// no model whole go to the locator of touching parts.
#include "picksight/vision/recognizer.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include "picksight/common/angles.hpp"
#include "picksight/vision/blob_features.hpp"
#include "picksight/vision/touching_parts.hpp"

namespace picksight::vision {
namespace {

// Phase of the region's complex moment of order k, degrees.
double regionPhaseDeg(const Region& region, int k) {
  if (k == 2) {
    const cv::Moments& m = region.moments;
    return std::atan2(2 * m.mu11, m.mu20 - m.mu02) * 180.0 / M_PI;
  }
  return std::arg(complexMoment(region, k)) * 180.0 / M_PI;
}

std::vector<double> candidates(double region_phase_deg, double model_phase_deg, int k) {
  if (k <= 0) return {0.0};
  std::vector<double> out;
  const double base = (region_phase_deg - model_phase_deg) / k;
  for (int j = 0; j < k; ++j) out.push_back(normalizeDeg(base + j * 360.0 / k));
  return out;
}

struct Best {
  double score = -1;
  double angle_deg = 0;  // reported
  double fit_deg = 0;    // where the boundary fits best: the score's, and the hand test's
};

// The moments' phase is as good as the part's direction is marked: on a
// nearly symmetric or nearly round part it is off by a degree or more,
// pixels at the rim. The best candidate is refined by descending the mean
// edge distance in ever finer turns.
constexpr double kRefineSpanDeg = 2.0;
constexpr double kRefineFinestDeg = 0.05;
// Candidates this far below the verify fraction are not worth refining.
constexpr double kRefineSlack = 0.3;
constexpr double kKeepMomentsDeg = 1.0;
// ... and verified within this fraction of the refined pose's score.
constexpr double kKeepMomentsSlack = 0.02;

Best bestOf(const std::vector<double>& turns, const PartModel& model, cv::Point2d centre,
            const EdgeDistance& edges, bool mirrored) {
  Best best;
  for (double t : turns) {
    const double s = verifyScore(model.samples, centre, t, edges, model.edge_tolerance, mirrored);
    if (s > best.score) best = {s, t, t};
  }
  if (best.score * 100 < model.verify_percent - 100 * kRefineSlack) return best;
  const double clip = 2 * model.edge_tolerance;
  const auto cost = [&](double t) {
    return meanEdgeDistance(model.samples, centre, t, edges, clip, mirrored);
  };
  double at = best.angle_deg;
  double here = cost(at);
  for (double step = kRefineSpanDeg / 2; step >= kRefineFinestDeg; step /= 2) {
    for (bool moved = true; moved;) {
      moved = false;
      for (double next : {at - step, at + step}) {
        const double c = cost(next);
        if (c < here - 1e-12) {
          here = c;
          at = next;
          moved = true;
        }
      }
      if (std::abs(at - best.angle_deg) > kRefineSpanDeg) break;
    }
  }
  // The verification is of the best pose; but where the moments were
  // close and verified about as well, their angle is the finer estimate
  // (every pixel of the part, against a distance map on the pixel grid,
  // biased by tenths of a degree) and is the one reported. A high order's
  // phase (a spoon's 6th) can be off by most of a degree: the pose that
  // fits is then the one reported, and the hands are always compared at
  // their fitted poses.
  const double s = verifyScore(model.samples, centre, at, edges, model.edge_tolerance, mirrored);
  if (s <= best.score) return best;
  const bool keep_moments =
      std::abs(at - best.angle_deg) < kKeepMomentsDeg && s - best.score <= kKeepMomentsSlack;
  best.score = s;
  best.fit_deg = normalizeDeg(at);
  if (!keep_moments) best.angle_deg = best.fit_deg;
  return best;
}

// What the recognizer needs of a region, computed on first use: models
// sharing an orientation order share the region's phase, and all share its
// edges.
struct RegionCache {
  bool hu_ready = false;
  HuArray log_hu{};
  std::unique_ptr<EdgeDistance> edges;
  std::map<int, double> phase_deg;  // by orientation order
};

double phaseOf(const Region& r, RegionCache& cache, int k) {
  if (k <= 0) return 0.0;
  const auto it = cache.phase_deg.find(k);
  if (it != cache.phase_deg.end()) return it->second;
  return cache.phase_deg[k] = regionPhaseDeg(r, k);
}

const HuArray& logHuOf(const Region& r, RegionCache& cache) {
  if (!cache.hu_ready) {
    cache.log_hu = logHu(huInvariants(r.moments));
    cache.hu_ready = true;
  }
  return cache.log_hu;
}

const EdgeDistance& edgesOf(const Region& r, RegionCache& cache, double margin) {
  if (!cache.edges) {
    std::vector<std::vector<cv::Point>> contours{r.outer};
    contours.insert(contours.end(), r.hole_boundaries.begin(), r.hole_boundaries.end());
    const int m = static_cast<int>(std::ceil(margin)) + 2;
    // Verification asks "within tolerance?" and the mirror test clips the
    // distance at twice the tolerance: nothing farther is ever read.
    cache.edges = std::make_unique<EdgeDistance>(
        contours, cv::Rect(r.bbox.x - m, r.bbox.y - m, r.bbox.width + 2 * m, r.bbox.height + 2 * m),
        2 * margin);
  }
  return *cache.edges;
}
}  // namespace

namespace {
// A region whose body looks like a model's (holes, Hu invariants) at an area
// between these squared scales is checked for a scaled copy of that model.
constexpr double kMinCopyScale = 0.6;
constexpr double kMaxCopyScale = 1.6;

// Whether the region is the model (either hand) scaled by `scale`: its
// boundary, scaled, verifies on the region's edges.
bool isScaledCopy(const Region& r, RegionCache& cache, const PartModel& model, double scale,
                  double max_tolerance) {
  std::vector<BoundarySample> scaled = model.samples;
  for (auto& s : scaled) {
    s.point *= scale;
  }
  const EdgeDistance& edges = edgesOf(r, cache, max_tolerance);
  const int k = model.orientation_order;
  const double phase = phaseOf(r, cache, k);
  for (const bool mirrored : {false, true}) {
    const double model_phase =
        mirrored ? -model.orientation_phase_deg : model.orientation_phase_deg;
    for (double t : candidates(phase, model_phase, k)) {
      const double v = verifyScore(scaled, r.centroid, t, edges, model.edge_tolerance, mirrored);
      if (v * 100 >= model.verify_percent) return true;
    }
  }
  return false;
}
}  // namespace

std::vector<double> rotationCandidates(const Region& region, const PartModel& model) {
  const int k = model.orientation_order;
  if (k <= 0) return {0.0};
  return candidates(regionPhaseDeg(region, k), model.orientation_phase_deg, k);
}

namespace {
// The parts in region i (see recognize).
std::vector<Match> recognizeRegion(const std::vector<Region>& regions, size_t i,
                                   const std::vector<const PartModel*>& models,
                                   double max_tolerance) {
  const Region& r = regions[i];
  RegionCache cache;
  Match best;
  // The region is one whole part, though of no model as trained (its
  // mirror image, or a copy of other size): no touching parts to look for.
  bool whole_part = false;
  for (const PartModel* model : models) {
    const BodyModel& body = model->body;
    if (r.holes != body.holes) continue;
    const double area_ratio = r.area / body.area;
    if (std::abs(area_ratio - 1) > body.area_tolerance) {
      if (!whole_part && area_ratio >= kMinCopyScale * kMinCopyScale &&
          area_ratio <= kMaxCopyScale * kMaxCopyScale &&
          huDistance(body, logHuOf(r, cache)) <= body.hu_tolerance) {
        whole_part = isScaledCopy(r, cache, *model, std::sqrt(area_ratio), max_tolerance);
      }
      continue;
    }
    const double distance = huDistance(body, logHuOf(r, cache));
    if (distance > body.hu_tolerance) continue;
    const EdgeDistance& edges = edgesOf(r, cache, max_tolerance);
    const int k = model->orientation_order;
    const double phase = phaseOf(r, cache, k);
    const Best direct = bestOf(candidates(phase, model->orientation_phase_deg, k), *model,
                               r.centroid, edges, false);
    if (direct.score * 100 < model->verify_percent) continue;
    if (!body.mirror_symmetric) {
      // The mirror image of the model, turned its own way, at its best
      // pose: where the two hands differ decides which one the region is.
      const Best mirror = bestOf(candidates(phase, -model->orientation_phase_deg, k), *model,
                                 r.centroid, edges, true);
      if (showsMirrorImage(*model, {r.centroid, direct.fit_deg, false},
                           {r.centroid, mirror.fit_deg, true}, edges)) {
        whole_part = true;
        continue;
      }
    }
    const bool better =
        direct.score > best.score + 1e-9 ||
        (std::abs(direct.score - best.score) <= 1e-9 && distance < best.body_distance);
    if (best.model && !better) continue;
    best.model = model;
    best.region = i;
    best.score = direct.score;
    best.centroid = r.centroid;
    best.symmetry_deg = model->symmetryDeg();
    best.angle_deg = wrapDeg(direct.angle_deg, best.symmetry_deg);
    best.body_distance = distance;
  }
  if (best.model) return {best};
  if (whole_part) return {};
  // No model explains the blob whole: parts that touch, or none.
  return locateInBlob(regions, i, models);
}
}  // namespace

std::vector<Match> recognize(const std::vector<Region>& regions,
                             const std::vector<const PartModel*>& models) {
  double max_tolerance = 0;
  for (const PartModel* m : models) max_tolerance = std::max(max_tolerance, m->edge_tolerance);
  // Regions are independent: all cores, each region writing its own slot,
  // gathered in region order so that the result does not depend on the
  // scheduling.
  std::vector<std::vector<Match>> per_region(regions.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(regions.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      per_region[static_cast<size_t>(i)] =
          recognizeRegion(regions, static_cast<size_t>(i), models, max_tolerance);
    }
  });
  std::vector<Match> matches;
  for (const auto& found : per_region) matches.insert(matches.end(), found.begin(), found.end());
  std::stable_sort(matches.begin(), matches.end(),
                   [](const Match& a, const Match& b) { return a.score > b.score; });
  return matches;
}

}  // namespace picksight::vision
