// Recognition: each separated region judged against every model
// (region_judge: body gates, rotation candidates verified on the boundary,
// the mirror test); the best verified model is the match, and blobs that no
// model explains whole go to the locator of touching parts.
#include "picksight/vision/recognition/recognizer.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "picksight/common/angles.hpp"
#include "picksight/vision/blob_search/touching_parts.hpp"
#include "picksight/vision/recognition/region_judge.hpp"

namespace picksight::vision {
namespace {
// A separated part's pose, read on its edges. The moments' phase and the
// descent on the distance map (region_judge) weigh pixels on a grid, and
// under front light the rim's coverage is uneven: a glint, a lit side or
// a blotch of the surface beside the part turns them by a tenth of a
// degree or more, and moves the area's centroid (every pixel of the rim
// read against a level the texture changes) by tenths of a pixel. The
// edge fit (the one that places touching parts) reads each stretch of edge
// on its own and leaves out those without a clean crossing, and places
// the model's outline, whose centre is the one every touching part of the
// type is placed by: separated and touching parts of a type are then
// placed alike, with the same offset the model was taught with.
// Front-light benchmark, 3 scenes of 20 parts, separated, position RMS
// px about each type's own offset (the part-to-part scatter), centroid
// against edge fit: clean 0.0085 / 0.0049, textured 0.020 / 0.007, glossy
// 0.045 / 0.013, wood 0.051 / 0.019, 30 grey levels 0.113 / 0.035, beside
// shadows 0.064 / 0.028, colour 0.029 / 0.009, brushed metal 0.026 /
// 0.010; against the drawn part, types taught on plain card: clean 0.0094
// / 0.0095, textured 0.025 / 0.012, glossy 0.064 / 0.026, wood 0.067 /
// 0.022, 30 levels 0.145 / 0.072. (Measured with models taught under the
// condition's light, before the shadows' light was read from the part,
// the centroid had looked as good: each model's teaching offset hid it.)
// A fit that does not settle, that turns farther than the judge's own
// refinement may, or moves farther than kMaxEdgeShiftPx from the area's
// centroid, leaves the judge's pose.
constexpr double kMinEdgeInliers = 0.5;
constexpr double kMaxEdgeTurnDeg = 2.0;
constexpr double kMaxEdgeShiftPx = 1.0;
// The judge's pose is within a pixel and a fraction of a degree: a search
// 2 px along the normals and one coarse pass before the two dense ones
// (touching parts, from rougher hypotheses, take 4 px and three more
// passes) gave the same turns to 0.0005 degree RMS on four front lights.
// The fit's cost, one thread, 20 separated parts, a loaded machine: the
// recognition's median 8.2 and 4.1 ms without it, 10.5 and 7.7 with these
// passes, 11.2 and 14.3 with the touching parts' (two runs each).
constexpr double kEdgeSearchPx = 2.0;
constexpr int kEdgeIterations = 3;

struct EdgePose {
  cv::Point2d centre;
  double angle_deg;
};

// A fit that moved farther than kMaxEdgeShiftPx (up to kMaxSettledShiftPx)
// is kept where a second fit from where it landed stays within
// kSettledPx and kSettledDeg of it: the area's centroid was off, not the
// fit. At 30 grey levels of contrast a part with one side in the light
// read its centroid 1.1 to 1.3 px off (the lit side's rim too faint for
// the band), the fit landed on the part's edges, and a second fit moved it
// 0.000 to 0.006 px more; it had been placed at the centroid, 1.2 px off,
// once its noise pinholes no longer sent it to the blob search. Beside a
// shadow 2-3 px of which stay joined along a long side (too thin for its
// layer to be cut), a bottle's centroid moved 2.1-2.8 px and its fit,
// settled 0.3-0.4 px from the part, was refused at 2 px: the front-light
// benchmark's 15 standard types beside shadows, separated, 0.32 px RMS,
// 0.10 with 3 (every other condition, and the unseen types, the same to
// the last digit). A fit that slid onto something else's edges does not
// settle so, or moves farther.
constexpr double kMaxSettledShiftPx = 3.0;
constexpr double kSettledPx = 0.05;
constexpr double kSettledDeg = 0.05;

EdgePose poseOnEdges(const PartModel& model, const Region& r, double judged_deg) {
  const EdgePose judged{r.centroid, judged_deg};
  const EdgeFit fit =
      refinePoseOnEdges(model, r, {r.centroid, judged_deg, false}, kEdgeSearchPx, kEdgeIterations);
  if (!fit.ok || fit.inlier_fraction < kMinEdgeInliers) return judged;
  const double turn = signedDeg(fit.pose.angle_deg - judged_deg);
  if (std::abs(turn) > kMaxEdgeTurnDeg) return judged;
  const double shift = cv::norm(fit.pose.centre - r.centroid);
  if (shift > kMaxSettledShiftPx) return judged;
  if (shift > kMaxEdgeShiftPx) {
    const EdgeFit again = refinePoseOnEdges(model, r, fit.pose, kEdgeSearchPx, kEdgeIterations);
    if (!again.ok || again.inlier_fraction < kMinEdgeInliers ||
        cv::norm(again.pose.centre - fit.pose.centre) > kSettledPx ||
        std::abs(signedDeg(again.pose.angle_deg - fit.pose.angle_deg)) > kSettledDeg) {
      return judged;
    }
  }
  return {fit.pose.centre, judged_deg + turn};
}

// The parts in region i (see recognize).
std::vector<Match> recognizeRegion(const std::vector<Region>& regions, size_t i,
                                   const std::vector<const PartModel*>& models,
                                   double max_tolerance) {
  const Region& r = regions[i];
  // Cut by the frame's edge, the region is no part whole: it may hold
  // parts whole, joined to what runs off the frame (the blob search places
  // only parts that lie inside it).
  if (r.touches_border) return locateInBlob(regions, i, models);
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
    const EdgePose pose = poseOnEdges(*best, r, best_verdict.angle_deg);
    match.centroid = pose.centre;
    match.symmetry_deg = best->symmetryDeg();
    match.angle_deg = reportedTurnDeg(*best, pose.angle_deg);
    match.body_distance = best_verdict.hu_distance;
    return {match};
  }
  if (whole_part) return {};
  // No model explains the blob whole: parts that touch, or none. What the
  // parts found leave is judged as a lone region would be: one whole copy
  // of a type that is no part (its mirror image, a larger copy) holds no
  // part, and is not searched; one part of a model is placed from the
  // reading's pose. Every model of a recognize() shares its hole setting,
  // which the piece is read with as the regions were.
  const LoneRegionTest read_rest = [&](const Region& piece) {
    return readLoneRegion(piece, models, max_tolerance);
  };
  return locateInBlob(regions, i, models, cache.builtEdges(), &read_rest);
}
}  // namespace

bool isWholeCopy(const Region& region, const std::vector<const PartModel*>& models,
                 double max_edge_tolerance) {
  return readLoneRegion(region, models, max_edge_tolerance).kind == LoneReading::Kind::kCopy;
}

LoneReading readLoneRegion(const Region& region, const std::vector<const PartModel*>& models,
                           double max_edge_tolerance) {
  LoneReading reading;
  if (models.empty()) return reading;
  const Region held = withHolesAtLeast(region, models.front()->min_hole_area);
  RegionCache cache(held, max_edge_tolerance);
  Verdict best;
  bool copy = false;
  bool smaller = false;
  for (const PartModel* model : models) {
    const Verdict v = judgeRegion(cache, *model, true);
    if (v.test == RegionTest::kPasses) {
      if (reading.model == nullptr || ranksAbove(v, best)) {
        reading.model = model;
        reading.angle_deg = v.angle_deg;
        best = v;
      }
      continue;
    }
    // Smaller than the part, a rest may be that part less what its
    // neighbours' drawn outlines took off it (a part 90 px long between
    // two others read at 0.93 of its model's scale, the bound 0.95): then
    // it is no copy, even where a smaller type of the same shape (a washer
    // of the next size down) finds it a larger copy of its own.
    smaller = smaller || (v.test == RegionTest::kScale && v.measured < v.low);
    copy = copy || v.test == RegionTest::kScale || v.test == RegionTest::kMirror;
  }
  if (reading.model != nullptr) {
    reading.kind = LoneReading::Kind::kPart;
  } else if (copy && !smaller) {
    reading.kind = LoneReading::Kind::kCopy;
  }
  return reading;
}

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
