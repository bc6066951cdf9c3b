// Recognition pass: the asked models' recognition (each with its own
// minimum hole area), and the screen of `LOCATE <type>` across every type.
#include "picksight/vision/recognition/recognition_pass.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "picksight/vision/recognition/recognizer.hpp"
#include "picksight/vision/recognition/region_judge.hpp"
#include "picksight/vision/segmentation/blob_features.hpp"

namespace picksight::vision {
namespace {
// A part of the asked type is screened out when another type's model is
// closer on the Hu distance (each in units of its model's tolerance) by
// this factor and this margin: two types of nearly one shape, or one part
// taught twice, tie, and a tie keeps the asked type.
constexpr double kCloserFactor = 2.0 / 3;
constexpr double kCloserMargin = 0.1;

double normalizedHu(const PartModel& m, const HuArray& log_hu) {
  return huDistance(m.body, log_hu) / std::max(m.body.hu_tolerance, 1e-12);
}

// The screen of one part of the asked type against the other types' models:
// the closest model of another type whose body tests (judgeBody: holes,
// area, Hu distance, the recognizer's own) the region passes, when it is
// clearly closer than the asked one.
std::optional<ScreenedOut> screen(const Match& match, const Region& region,
                                  const std::vector<const PartModel*>& others) {
  // Body tests only: the edge map, which needs a tolerance, is never built.
  RegionCache cache(region, 0);
  ScreenedOut out;
  out.region = match.region;
  out.asked = match.model;
  out.asked_distance = normalizedHu(*match.model, cache.logHu());
  for (const PartModel* m : others) {
    const Verdict body = judgeBody(cache, *m, holesAtLeast(region, m->min_hole_area));
    if (body.test != RegionTest::kPasses) continue;
    const double d = body.hu_distance / std::max(m->body.hu_tolerance, 1e-12);
    if (d >= kCloserFactor * out.asked_distance || out.asked_distance - d <= kCloserMargin) {
      continue;
    }
    if (!out.closer || d < out.closer_distance) {
      out.closer = m;
      out.closer_distance = d;
    }
  }
  if (!out.closer) return std::nullopt;
  return out;
}
}  // namespace

RegionOptions regionOptionsFor(const RegionOptions& cell, const std::vector<PartModel>& models) {
  RegionOptions o = cell;
  double smallest_part = 0;
  for (const auto& m : models) {
    o.min_hole_area = std::min(o.min_hole_area, m.min_hole_area);
    if (m.min_region_area > 0) o.min_area = std::min(o.min_area, m.min_region_area);
    // The smallest a part of the model may be (the blob search's own bound).
    const double part = m.body.area * (1 - m.body.area_tolerance);
    if (smallest_part == 0 || part < smallest_part) smallest_part = part;
  }
  // A region at the frame's edge may hold a whole part (see
  // RegionOptions::border_min_area) when it is as large as one.
  if (!models.empty()) o.border_min_area = std::max(smallest_part, 1.0);
  return o;
}

double speckAreaFor(const std::vector<PartModel>& models) {
  // A part half hidden under another, or the smaller of two scaled copies,
  // is still ten times this; the coarse grain of a textured belt is not.
  constexpr double kSpeckShare = 0.05;
  double smallest = 0;
  for (const auto& m : models) {
    if (smallest == 0 || m.body.area < smallest) smallest = m.body.area;
  }
  return kSpeckShare * smallest;
}

RecognitionPass recognizeParts(const std::vector<Region>& regions,
                               const std::vector<PartModel>& models, int type) {
  std::vector<const PartModel*> asked;
  std::vector<const PartModel*> others;
  for (const auto& m : models) (type < 0 || m.type == type ? asked : others).push_back(&m);
  RecognitionPass pass;
  // Each model judging holes with its own minimum hole area.
  pass.matches = recognizeEachHoleSetting(regions, asked);
  if (type < 0 || others.empty()) return pass;
  // A part found by the touching search is screened on its whole region
  // too: a blob of several parts passes no single model's area test, while
  // one whole part of another type, which the asked model's boundary half
  // fits, does.
  std::vector<Match> kept;
  kept.reserve(pass.matches.size());
  for (auto& m : pass.matches) {
    const auto out = screen(m, regions[m.region], others);
    if (out) {
      pass.screened_out.push_back(*out);
    } else {
      kept.push_back(std::move(m));
    }
  }
  pass.matches = std::move(kept);
  return pass;
}

}  // namespace picksight::vision
