// Recognition pass: per-model minimum hole areas, and the screen of
// `LOCATE <type>` across every type.
#include "picksight/cell/recognition_pass.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include "picksight/vision/recognition/region_judge.hpp"
#include "picksight/vision/segmentation/blob_features.hpp"

namespace picksight::app {
namespace {
// A part of the asked type is screened out when another type's model is
// closer on the Hu distance (each in units of its model's tolerance) by
// this factor and this margin: two types of nearly one shape, or one part
// taught twice, tie, and a tie keeps the asked type.
constexpr double kCloserFactor = 2.0 / 3;
constexpr double kCloserMargin = 0.1;

// Where models of several hole settings found parts in one region, the
// setting whose best part there scores highest keeps the region: as when
// every model competes in one recognize().
std::vector<vision::Match> oneSettingPerRegion(std::vector<std::pair<size_t, vision::Match>> all) {
  std::map<size_t, std::pair<size_t, double>> best;  // region -> (setting, score)
  for (const auto& [setting, m] : all) {
    auto it = best.find(m.region);
    if (it == best.end() || m.score > it->second.second) best[m.region] = {setting, m.score};
  }
  std::vector<vision::Match> out;
  for (auto& [setting, m] : all)
    if (best[m.region].first == setting) out.push_back(std::move(m));
  return out;
}

double normalizedHu(const vision::PartModel& m, const vision::HuArray& log_hu) {
  return vision::huDistance(m.body, log_hu) / std::max(m.body.hu_tolerance, 1e-12);
}

// The screen of one part of the asked type against the other types' models:
// the closest model of another type whose area, hole count and Hu tests
// the region passes, when it is clearly closer than the asked one.
std::optional<ScreenedOut> screen(const vision::Match& match, const vision::Region& region,
                                  const std::vector<const vision::PartModel*>& others) {
  const vision::HuArray log_hu = vision::logHu(vision::huInvariants(region.moments));
  ScreenedOut out;
  out.region = match.region;
  out.asked = match.model;
  out.asked_distance = normalizedHu(*match.model, log_hu);
  for (const vision::PartModel* m : others) {
    const vision::BodyModel& body = m->body;
    if (vision::holesAtLeast(region, m->min_hole_area) != body.holes) continue;
    if (std::abs(region.area - body.area) > body.area_tolerance * body.area) continue;
    const double d = normalizedHu(*m, log_hu);
    if (d > 1 || d >= kCloserFactor * out.asked_distance ||
        out.asked_distance - d <= kCloserMargin) {
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

vision::RegionOptions regionOptionsFor(const vision::RegionOptions& cell,
                                       const std::vector<vision::PartModel>& models) {
  vision::RegionOptions o = cell;
  for (const auto& m : models) {
    o.min_hole_area = std::min(o.min_hole_area, m.min_hole_area);
    if (m.min_region_area > 0) o.min_area = std::min(o.min_area, m.min_region_area);
  }
  return o;
}

RecognitionPass recognizeParts(const std::vector<vision::Region>& regions,
                               const std::vector<vision::PartModel>& models, int type) {
  // The asked models by their minimum hole area: one recognize() per
  // setting, on the regions as that setting sees them.
  std::map<double, std::vector<const vision::PartModel*>> settings;
  std::vector<const vision::PartModel*> others;
  for (const auto& m : models) {
    if (type < 0 || m.type == type) {
      settings[m.min_hole_area].push_back(&m);
    } else {
      others.push_back(&m);
    }
  }
  RecognitionPass pass;
  if (settings.size() == 1) {
    const auto& [min_hole_area, list] = *settings.begin();
    pass.matches = vision::hasHoleBelow(regions, min_hole_area)
                       ? vision::recognize(vision::withHolesAtLeast(regions, min_hole_area), list)
                       : vision::recognize(regions, list);
  } else {
    std::vector<std::pair<size_t, vision::Match>> all;
    size_t setting = 0;
    for (const auto& [min_hole_area, list] : settings) {
      auto found = vision::hasHoleBelow(regions, min_hole_area)
                       ? vision::recognize(vision::withHolesAtLeast(regions, min_hole_area), list)
                       : vision::recognize(regions, list);
      for (auto& m : found) all.emplace_back(setting, std::move(m));
      ++setting;
    }
    pass.matches = oneSettingPerRegion(std::move(all));
    std::stable_sort(
        pass.matches.begin(), pass.matches.end(),
        [](const vision::Match& a, const vision::Match& b) { return a.score > b.score; });
  }
  if (type < 0 || others.empty()) return pass;
  // A part found by the touching search is screened on its whole region
  // too: a blob of several parts passes no single model's area test, while
  // one whole part of another type, which the asked model's boundary half
  // fits, does.
  std::vector<vision::Match> kept;
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

}  // namespace picksight::app
