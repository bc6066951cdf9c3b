// Recognition: separated parts through body gates (holes, area, Hu distance,
// the sign of the 7th invariant), rotation candidates from complex moments
// and the boundary model verified at each candidate pose; blobs that match
// no model whole go to the locator of touching parts.
#include "picksight/vision/recognizer.hpp"

#include <algorithm>
#include <cmath>
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
  double angle_deg = 0;
};

Best bestOf(const std::vector<double>& turns, const PartModel& model, cv::Point2d centre,
            const EdgeDistance& edges, bool mirrored) {
  Best best;
  for (double t : turns) {
    const double s = verifyScore(model.samples, centre, t, edges, model.edge_tolerance, mirrored);
    if (s > best.score) best = {s, t};
  }
  return best;
}

// What the recognizer needs of a region, computed on first use.
struct RegionCache {
  bool hu_ready = false;
  HuArray log_hu{};
  std::unique_ptr<EdgeDistance> edges;
};

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
  for (const PartModel* model : models) {
    const BodyModel& body = model->body;
    if (r.holes != body.holes) continue;
    if (std::abs(r.area - body.area) > body.area_tolerance * body.area) continue;
    if (!cache.hu_ready) {
      cache.log_hu = logHu(huInvariants(r.moments));
      cache.hu_ready = true;
    }
    const double distance = huDistance(body, cache.log_hu);
    if (distance > body.hu_tolerance) continue;
    // The 7th invariant changes sign in a mirror: where the model's is
    // stable, a part with the other sign is the mirror image.
    if (!body.mirror_symmetric && body.hu_used[6] &&
        (cache.log_hu[6] >= 0) != (body.log_hu[6] >= 0))
      continue;

    const EdgeDistance& edges = edgesOf(r, cache, max_tolerance);
    const int k = model->orientation_order;
    const double phase = k > 0 ? regionPhaseDeg(r, k) : 0.0;
    const Best direct = bestOf(candidates(phase, model->orientation_phase_deg, k), *model,
                               r.centroid, edges, false);
    if (direct.score * 100 < model->verify_percent) continue;
    if (!body.mirror_symmetric) {
      // The mirror image of the model, turned its own way, at its best
      // pose: where the two hands differ decides which one the region is.
      const Best mirror = bestOf(candidates(phase, -model->orientation_phase_deg, k), *model,
                                 r.centroid, edges, true);
      if (showsMirrorImage(*model, {r.centroid, direct.angle_deg, false},
                           {r.centroid, mirror.angle_deg, true}, edges)) {
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
