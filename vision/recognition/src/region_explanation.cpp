// Region explanations: every model's verdict on the region (judgeRegion,
// the recognizer's tests), the nearest model's named.
#include "picksight/vision/recognition/region_explanation.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace picksight::vision {

RegionExplanation explainRegion(const Region& region, const std::vector<const PartModel*>& models) {
  RegionExplanation best;
  if (models.empty()) return best;
  double max_tolerance = 0;
  for (const PartModel* m : models) max_tolerance = std::max(max_tolerance, m->edge_tolerance);
  // The models by their minimum hole area: each setting sees the region as
  // recognition gives it to those models (its smaller holes left out).
  std::map<double, std::vector<const PartModel*>> settings;
  for (const PartModel* m : models) settings[m->min_hole_area].push_back(m);

  double best_area_gap = 0;
  double best_score = -1;
  double best_distance = 0;
  const auto consider = [&](const PartModel* model, const Verdict& v) {
    const double gap = std::abs(region.area - model->body.area) / std::max(model->body.area, 1.0);
    bool nearer = !best.nearest || static_cast<int>(v.test) > static_cast<int>(best.test);
    if (best.nearest && v.test == best.test) {
      // Passing models rank as recognize() ranks them: score, then Hu distance.
      nearer = v.test != RegionTest::kPasses           ? gap < best_area_gap
               : std::abs(v.score - best_score) > 1e-9 ? v.score > best_score
                                                       : v.hu_distance < best_distance;
    }
    if (!nearer) return;
    best.nearest = model;
    best.test = v.test;
    best.measured = v.measured;
    best.low = v.low;
    best.high = v.high;
    best_area_gap = gap;
    best_score = v.score;
    best_distance = v.hu_distance;
  };
  for (const auto& [min_hole_area, list] : settings) {
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

}  // namespace picksight::vision
