// Recognition: each separated region judged against every model
// (region_judge: body gates, rotation candidates verified on the boundary,
// the mirror test); the best verified model is the match, and blobs that no
// model explains whole go to the locator of touching parts.
#include "picksight/vision/recognition/recognizer.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

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
  const PartModel* best = nullptr;
  Verdict best_verdict;
  // The region is one whole part, though of no model as trained (its
  // mirror image, or a copy of other size): no touching parts to look for.
  bool whole_part = false;
  for (const PartModel* model : models) {
    const Verdict v = judgeRegion(cache, *model, !whole_part);
    if (v.test == RegionTest::kScale || v.test == RegionTest::kMirror) whole_part = true;
    if (v.test != RegionTest::kPasses) continue;
    if (best && !ranksAbove(v, best_verdict)) continue;
    best = model;
    best_verdict = v;
  }
  if (best) {
    Match match;
    match.model = best;
    match.region = i;
    match.score = best_verdict.score;
    match.centroid = r.centroid;
    match.symmetry_deg = best->symmetryDeg();
    match.angle_deg = reportedTurnDeg(*best, best_verdict.angle_deg);
    match.body_distance = best_verdict.hu_distance;
    return {match};
  }
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

std::vector<Match> recognizeEachHoleSetting(const std::vector<Region>& regions,
                                            const std::vector<const PartModel*>& models) {
  const auto settings = byMinHoleArea(models);
  // One recognize() per setting, on the regions as that setting sees them.
  const auto recognizeSetting = [&](double min_hole_area,
                                    const std::vector<const PartModel*>& list) {
    return hasHoleBelow(regions, min_hole_area)
               ? recognize(withHolesAtLeast(regions, min_hole_area), list)
               : recognize(regions, list);
  };
  if (settings.empty()) return {};
  if (settings.size() == 1)
    return recognizeSetting(settings.begin()->first, settings.begin()->second);
  // Where models of several settings found parts in one region, the
  // setting whose best part there scores highest keeps the region: as when
  // every model competes in one recognize().
  std::vector<std::pair<size_t, Match>> all;
  size_t setting = 0;
  for (const auto& [min_hole_area, list] : settings) {
    for (auto& m : recognizeSetting(min_hole_area, list)) all.emplace_back(setting, std::move(m));
    ++setting;
  }
  std::map<size_t, std::pair<size_t, double>> best;  // region -> (setting, score)
  for (const auto& [in_setting, m] : all) {
    auto it = best.find(m.region);
    if (it == best.end() || m.score > it->second.second) best[m.region] = {in_setting, m.score};
  }
  std::vector<Match> matches;
  for (auto& [in_setting, m] : all)
    if (best[m.region].first == in_setting) matches.push_back(std::move(m));
  std::stable_sort(matches.begin(), matches.end(),
                   [](const Match& u, const Match& v) { return u.score > v.score; });
  return matches;
}

}  // namespace picksight::vision
