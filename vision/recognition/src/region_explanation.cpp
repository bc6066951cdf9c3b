// Region explanations: every model's verdict on the region (judgeRegion,
// the recognizer's tests), the nearest model's named.
#include "picksight/vision/recognition/region_explanation.hpp"

#include <algorithm>
#include <cmath>

namespace picksight::vision {

RegionExplanation explainRegion(const Region& region, const std::vector<const PartModel*>& models) {
  RegionExplanation best;
  if (models.empty()) return best;
  double max_tolerance = 0;
  for (const PartModel* m : models) max_tolerance = std::max(max_tolerance, m->edge_tolerance);
  double best_area_gap = 0;
  Verdict best_verdict;
  const auto consider = [&](const PartModel* model, const Verdict& v) {
    const double gap = std::abs(region.area - model->body.area) / std::max(model->body.area, 1.0);
    bool nearer = !best.nearest || static_cast<int>(v.test) > static_cast<int>(best.test);
    if (best.nearest && v.test == best.test) {
      // Passing models rank as recognize() ranks them.
      nearer = v.test != RegionTest::kPasses ? gap < best_area_gap : ranksAbove(v, best_verdict);
    }
    if (!nearer) return;
    best.nearest = model;
    best.test = v.test;
    best.measured = v.measured;
    best.low = v.low;
    best.high = v.high;
    best_area_gap = gap;
    best_verdict = v;
  };
  // Each setting sees the region as recognition gives it to its models
  // (its smaller holes left out).
  for (const auto& [min_hole_area, list] : byMinHoleArea(models)) {
    if (region.touches_border) {
      for (const PartModel* m : list) consider(m, Verdict{RegionTest::kEdge});
      continue;
    }
    const bool fewer = holesAtLeast(region, min_hole_area) != region.holes;
    const Region seen = fewer ? withHolesAtLeast(region, min_hole_area) : Region();
    RegionCache cache(fewer ? seen : region, max_tolerance);
    for (const PartModel* m : list) consider(m, judgeRegion(cache, *m));
  }
  return best;
}

RegionExplanation explainRegionAsAsked(const Region& region,
                                       const std::vector<const PartModel*>& models,
                                       int asked_type) {
  RegionExplanation e = explainRegion(region, models);
  if (asked_type < 0) return e;
  if (e.test == RegionTest::kPasses && e.nearest && e.nearest->type != asked_type) {
    e.other_type = true;
    return e;
  }
  std::vector<const PartModel*> asked;
  for (const PartModel* m : models)
    if (m->type == asked_type) asked.push_back(m);
  return explainRegion(region, asked);
}

}  // namespace picksight::vision
