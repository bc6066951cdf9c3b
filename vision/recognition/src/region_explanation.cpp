// Region explanations: every model's verdict on the region (judgeRegion,
// the recognizer's tests), the nearest model's named; the remedy that
// would accept it, checked through the cell's recognition pass.
#include "picksight/vision/recognition/region_explanation.hpp"

#include <algorithm>
#include <cmath>

#include "picksight/vision/recognition/recognition_pass.hpp"

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

bool unlikeEveryModel(const Region& region, const std::vector<const PartModel*>& models) {
  if (models.empty()) return false;
  RegionCache cache(region, 0);
  for (const PartModel* m : models) {
    const BodyModel& body = m->body;
    const double gap = region.area - body.area;
    const double allowed =
        kUnlikeTolerances * std::max(body.area_tolerance, kUnlikeMinAreaTolerance) * body.area;
    if (region.touches_border) {
      // The frame hides an unknown share of the region: area and holes
      // beyond it, never more of either than the part has.
      if (gap <= allowed && holesAtLeast(region, m->min_hole_area) <= body.holes) return false;
      continue;
    }
    const bool far_shape = huDistance(body, cache.logHu()) >
                           kUnlikeTolerances * std::max(body.hu_tolerance, kUnlikeMinHuTolerance);
    const double ratio = region.area / body.area;
    // A copy has the part's holes, and at most a speckle's more (a belt's
    // blotch the threshold took in, of a part's shape and size, had 16).
    const bool copy_size = ratio >= kUnlikeMinCopyArea && ratio <= kUnlikeMaxCopyArea &&
                           holesAtLeast(region, m->min_hole_area) <= body.holes + 1;
    if (!far_shape && (std::abs(gap) <= allowed || copy_size)) return false;
  }
  return true;
}

namespace {
// A tolerance written with this many decimals: the value TOLERANCE reads
// back is the one checked here.
constexpr int kRemedyDecimals = 3;
constexpr int kRemedyPercentDecimals = 1;
// Below this a remedy is rounding noise of the measured value.
constexpr double kRemedySlack = 1e-9;
// A remedy admits the measured value with a margin: a Hu distance or an
// area's relative gap this much larger, a verified share this many points
// lower. The next frame of a live camera measures the region again, a
// little differently; a bound set exactly on this frame's value would
// refuse the region as often as not.
constexpr double kRemedyMargin = 0.1;
constexpr double kRemedyVerifyPoints = 2;

double roundUp(double v, int decimals) {
  const double f = std::pow(10.0, decimals);
  return std::ceil((v + kRemedySlack) * f) / f;
}

double roundDown(double v, int decimals) {
  const double f = std::pow(10.0, decimals);
  return std::floor((v - kRemedySlack) * f) / f;
}

// The change of `model` that admits the measured value of `why`, within
// the bounds TOLERANCE accepts; none for tests no tolerance decides.
std::optional<RegionRemedy> candidateRemedy(const RegionExplanation& why, const PartModel& model) {
  RegionRemedy r;
  r.type = model.type;
  r.decimals = kRemedyDecimals;
  switch (why.test) {
    case RegionTest::kArea:
    case RegionTest::kScale: {
      // The area against the model's; a scaled copy's is its scale squared.
      r.key = "area_tolerance";
      const double ratio = why.test == RegionTest::kArea
                               ? why.measured / std::max(model.body.area, 1.0)
                               : why.measured * why.measured;
      r.value = roundUp(std::abs(ratio - 1) * (1 + kRemedyMargin), r.decimals);
      if (r.value >= 1) return std::nullopt;  // area_tolerance is below 1
      return r;
    }
    case RegionTest::kHu:
      r.key = "hu_tolerance";
      r.value = roundUp(why.measured * (1 + kRemedyMargin), r.decimals);
      if (r.value > 100) return std::nullopt;
      return r;
    case RegionTest::kVerify:
      r.key = "verify_percent";
      r.decimals = kRemedyPercentDecimals;
      r.value = roundDown(why.measured - kRemedyVerifyPoints, r.decimals);
      if (r.value <= 0) return std::nullopt;
      return r;
    case RegionTest::kMirror:
      r.key = "mirror_symmetric";
      r.decimals = 0;
      r.value = 1;
      return r;
    default:
      return std::nullopt;
  }
}

void applyRemedy(PartModel& model, const RegionRemedy& r) {
  const std::string key = r.key;
  if (key == "area_tolerance") model.body.area_tolerance = r.value;
  if (key == "hu_tolerance") model.body.hu_tolerance = r.value;
  if (key == "verify_percent") model.verify_percent = r.value;
  if (key == "mirror_symmetric") model.body.mirror_symmetric = r.value != 0;
}
}  // namespace

std::optional<RegionRemedy> remedyFor(const Region& region, const std::vector<PartModel>& models,
                                      const RegionExplanation& why, int asked_type) {
  if (!why.nearest || why.other_type) return std::nullopt;
  size_t index = 0;
  while (index < models.size() && &models[index] != why.nearest) ++index;
  if (index == models.size()) return std::nullopt;
  const auto remedy = candidateRemedy(why, *why.nearest);
  if (!remedy) return std::nullopt;
  std::vector<PartModel> changed = models;
  applyRemedy(changed[index], *remedy);
  // The changed model's own verdict first: a region another test still
  // refuses costs no touching-parts search.
  const PartModel& model = changed[index];
  const Region seen = withHolesAtLeast(region, model.min_hole_area);
  RegionCache cache(seen, model.edge_tolerance);
  if (judgeRegion(cache, model).test != RegionTest::kPasses) return std::nullopt;
  // Then LOCATE's own pass on the region (every model, the screen of
  // LOCATE <type> across types): a part there is a part LOCATE reports.
  if (recognizeParts({region}, changed, asked_type).matches.empty()) return std::nullopt;
  return remedy;
}

}  // namespace picksight::vision
