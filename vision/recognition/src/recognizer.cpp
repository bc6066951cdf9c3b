// Recognition: each separated region judged against every model
// (region_judge: body gates, rotation candidates verified on the boundary,
// the mirror test); the best verified model is the match, and blobs that no
// model explains whole go to the locator of touching parts.
#include "picksight/vision/recognition/recognizer.hpp"

#include <algorithm>
#include <cmath>

#include "picksight/common/angles.hpp"
#include "picksight/vision/blob_search/touching_parts.hpp"
#include "picksight/vision/recognition/region_judge.hpp"

namespace picksight::vision {
namespace {
// The parts in region i (see recognize).
std::vector<Match> recognizeRegion(const std::vector<Region>& regions, size_t i,
                                   const std::vector<const PartModel*>& models,
                                   double max_tolerance) {
  const Region& r = regions[i];
  RegionCache cache(r, max_tolerance);
  Match best;
  // The region is one whole part, though of no model as trained (its
  // mirror image, or a copy of other size): no touching parts to look for.
  bool whole_part = false;
  for (const PartModel* model : models) {
    const Verdict v = judgeRegion(cache, *model, !whole_part);
    if (v.test == RegionTest::kScale || v.test == RegionTest::kMirror) whole_part = true;
    if (v.test != RegionTest::kPasses) continue;
    const bool better = v.score > best.score + 1e-9 || (std::abs(v.score - best.score) <= 1e-9 &&
                                                        v.hu_distance < best.body_distance);
    if (best.model && !better) continue;
    best.model = model;
    best.region = i;
    best.score = v.score;
    best.centroid = r.centroid;
    best.symmetry_deg = model->symmetryDeg();
    best.angle_deg = wrapDeg(v.angle_deg, best.symmetry_deg);
    best.body_distance = v.hu_distance;
  }
  if (best.model) return {best};
  if (whole_part) return {};
  // No model explains the blob whole: parts that touch, or none.
  return locateInBlob(regions, i, models, cache.builtEdges());
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
