// Region verdicts: body gates (holes, area, Hu distance), the scaled-copy
// search, rotation candidates from complex moments refined on the edges,
// and the mirror test on the boundary.
#include "picksight/vision/recognition/region_judge.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "picksight/common/angles.hpp"

namespace picksight::vision {

const char* regionTestName(RegionTest test) {
  switch (test) {
    case RegionTest::kEdge:
      return "edge";
    case RegionTest::kHoles:
      return "holes";
    case RegionTest::kArea:
      return "area";
    case RegionTest::kHu:
      return "hu";
    case RegionTest::kVerify:
      return "verify";
    case RegionTest::kScale:
      return "scale";
    case RegionTest::kMirror:
      return "mirror";
    case RegionTest::kPasses:
      return "passes";
  }
  return "passes";
}

int holesAtLeast(const Region& region, double min_hole_area) {
  if (min_hole_area <= 0) return region.holes;
  int n = 0;
  for (const auto& h : region.hole_boundaries) n += cv::contourArea(h) >= min_hole_area ? 1 : 0;
  return n;
}

bool hasHoleBelow(const std::vector<Region>& regions, double min_hole_area) {
  for (const auto& r : regions)
    if (holesAtLeast(r, min_hole_area) != r.holes) return true;
  return false;
}

Region withHolesAtLeast(const Region& region, double min_hole_area) {
  Region out = region;
  auto& holes = out.hole_boundaries;
  holes.erase(std::remove_if(holes.begin(), holes.end(),
                             [&](const std::vector<cv::Point>& h) {
                               return cv::contourArea(h) < min_hole_area;
                             }),
              holes.end());
  out.holes = static_cast<int>(holes.size());
  return out;
}

std::vector<Region> withHolesAtLeast(const std::vector<Region>& regions, double min_hole_area) {
  std::vector<Region> out;
  out.reserve(regions.size());
  for (const auto& r : regions) out.push_back(withHolesAtLeast(r, min_hole_area));
  return out;
}

RegionCache::RegionCache(const Region& region, double max_edge_tolerance)
    : region_(region), max_edge_tolerance_(max_edge_tolerance) {}

const HuArray& RegionCache::logHu() {
  if (!hu_ready_) {
    log_hu_ = vision::logHu(huInvariants(region_.moments));
    hu_ready_ = true;
  }
  return log_hu_;
}

const EdgeDistance& RegionCache::edges() {
  if (!edges_) {
    std::vector<std::vector<cv::Point>> contours{region_.outer};
    contours.insert(contours.end(), region_.hole_boundaries.begin(), region_.hole_boundaries.end());
    // Verification asks "within tolerance?" and the refinement and the
    // mirror test clip the distance at twice the tolerance: nothing farther
    // is ever read. The box reaches that far past the region's, so that a
    // model's verdict does not depend on the other models judged with it.
    const double reach = 2 * max_edge_tolerance_;
    const int m = static_cast<int>(std::ceil(reach)) + 1;
    const cv::Rect& box = region_.bbox;
    edges_ = std::make_unique<EdgeDistance>(
        contours, cv::Rect(box.x - m, box.y - m, box.width + 2 * m, box.height + 2 * m), reach);
  }
  return *edges_;
}

double RegionCache::phaseDeg(int k) {
  if (k <= 0) return 0.0;
  const auto it = phase_deg_.find(k);
  if (it != phase_deg_.end()) return it->second;
  double phase = 0;
  if (k == 2) {
    const cv::Moments& m = region_.moments;
    phase = std::atan2(2 * m.mu11, m.mu20 - m.mu02) * 180.0 / M_PI;
  } else {
    phase = std::arg(complexMoment(region_, k)) * 180.0 / M_PI;
  }
  return phase_deg_[k] = phase;
}

namespace {

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

// The best verified of the rotation candidates, unrefined: the model's
// boundary `samples` (its own, or scaled: see kMinScaledVerify).
Best bestCandidate(const std::vector<double>& turns, const PartModel& model,
                   const std::vector<BoundarySample>& samples, cv::Point2d centre,
                   const EdgeDistance& edges, bool mirrored) {
  Best best;
  for (double t : turns) {
    const double s = verifyScore(samples, centre, t, edges, model.edge_tolerance, mirrored);
    if (s > best.score) best = {s, t, t};
  }
  return best;
}

Best bestOf(const std::vector<double>& turns, const PartModel& model,
            const std::vector<BoundarySample>& samples, cv::Point2d centre,
            const EdgeDistance& edges, bool mirrored) {
  Best best = bestCandidate(turns, model, samples, centre, edges, mirrored);
  if (best.score * 100 < model.verify_percent - 100 * kRefineSlack) return best;
  const double clip = 2 * model.edge_tolerance;
  const auto cost = [&](double t) {
    return meanEdgeDistance(samples, centre, t, edges, clip, mirrored);
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
  const double s = verifyScore(samples, centre, at, edges, model.edge_tolerance, mirrored);
  if (s <= best.score) return best;
  const bool keep_moments =
      std::abs(at - best.angle_deg) < kKeepMomentsDeg && s - best.score <= kKeepMomentsSlack;
  best.score = s;
  best.fit_deg = normalizeDeg(at);
  if (!keep_moments) best.angle_deg = best.fit_deg;
  return best;
}

// A region whose body looks like a model's (holes, Hu invariants) at an area
// between these squared scales is checked for a scaled copy of that model.
constexpr double kMinCopyScale = 0.6;
constexpr double kMaxCopyScale = 1.6;

// A region whose area puts its scale this far from the model's (within the
// area tolerance) and that does not verify at the model's size is verified
// at its own: its boundary at the region's scale. Past a few percent the
// ends of a long part lie outside the edge tolerance at the taught size
// (a bar 200 px long, 8 % larger: 8 px at each end, 70 % of its boundary
// verified). Below it, the area's own reading (the band, the light) moves
// the scale as much as the part does.
constexpr double kMinScaledVerify = 0.02;
// Verified at its own size, a region is left out as a mirror image when
// the mirror image verifies within this of the part there.
constexpr double kScaledMirrorMargin = 0.03;

// Whether the region is the model (either hand) scaled by `scale`: its
// boundary, scaled, verifies on the region's edges.
bool isScaledCopy(RegionCache& cache, const PartModel& model, double scale) {
  std::vector<BoundarySample> scaled = model.samples;
  double total = 0;
  for (auto& s : scaled) {
    s.point *= scale;
    total += s.weight;
  }
  const Region& r = cache.region();
  const EdgeDistance& edges = cache.edges();
  const int k = model.orientation_order;
  const double phase = cache.phaseDeg(k);
  for (const bool mirrored : {false, true}) {
    const double model_phase =
        mirrored ? -model.orientation_phase_deg : model.orientation_phase_deg;
    for (double t : candidates(phase, model_phase, k)) {
      // A yes or no: the walk along the boundary stops once it is decided.
      if (verifiesAtLeast(scaled, total, r.centroid, std::cos(t * kRadPerDeg),
                          std::sin(t * kRadPerDeg), mirrored ? -1.0 : 1.0, edges,
                          model.edge_tolerance, model.verify_percent / 100.0))
        return true;
    }
  }
  return false;
}

Verdict failed(RegionTest test, double measured, double low, double high) {
  Verdict v;
  v.test = test;
  v.measured = measured;
  v.low = low;
  v.high = high;
  return v;
}
}  // namespace

Verdict judgeBody(RegionCache& cache, const PartModel& model, int holes) {
  const Region& r = cache.region();
  const BodyModel& body = model.body;
  if (holes != body.holes) return failed(RegionTest::kHoles, holes, body.holes, body.holes);
  const double area_ratio = r.area / body.area;
  if (std::abs(area_ratio - 1) > body.area_tolerance) {
    return failed(RegionTest::kArea, r.area, body.area * (1 - body.area_tolerance),
                  body.area * (1 + body.area_tolerance));
  }
  const double distance = huDistance(body, cache.logHu());
  if (distance > body.hu_tolerance) {
    return failed(RegionTest::kHu, distance, body.hu_tolerance, body.hu_tolerance);
  }
  Verdict v;
  v.hu_distance = distance;
  return v;
}

bool ranksAbove(const Verdict& a, const Verdict& b) {
  return a.score > b.score + 1e-9 ||
         (std::abs(a.score - b.score) <= 1e-9 && a.hu_distance < b.hu_distance);
}

std::map<double, std::vector<const PartModel*>> byMinHoleArea(
    const std::vector<const PartModel*>& models) {
  std::map<double, std::vector<const PartModel*>> settings;
  for (const PartModel* m : models) settings[m->min_hole_area].push_back(m);
  return settings;
}

Verdict judgeRegion(RegionCache& cache, const PartModel& model, bool check_scale) {
  const Region& r = cache.region();
  const BodyModel& body = model.body;
  const Verdict gates = judgeBody(cache, model, r.holes);
  if (gates.test == RegionTest::kArea) {
    // Outside the area tolerance, a body and boundary that fit the model
    // scaled make the region a scaled copy: a whole part, not a blob.
    const double area_ratio = r.area / body.area;
    if (check_scale && area_ratio >= kMinCopyScale * kMinCopyScale &&
        area_ratio <= kMaxCopyScale * kMaxCopyScale &&
        huDistance(body, cache.logHu()) <= body.hu_tolerance &&
        isScaledCopy(cache, model, std::sqrt(area_ratio))) {
      return failed(RegionTest::kScale, std::sqrt(area_ratio), std::sqrt(1 - body.area_tolerance),
                    std::sqrt(1 + body.area_tolerance));
    }
  }
  if (gates.test != RegionTest::kPasses) return gates;
  const double distance = gates.hu_distance;
  const EdgeDistance& edges = cache.edges();
  const int k = model.orientation_order;
  const double phase = cache.phaseDeg(k);
  const std::vector<double> direct_turns = candidates(phase, model.orientation_phase_deg, k);
  const std::vector<double> mirror_turns = candidates(phase, -model.orientation_phase_deg, k);
  Best direct = bestOf(direct_turns, model, model.samples, r.centroid, edges, false);
  Verdict v;
  v.hu_distance = distance;
  v.low = v.high = model.verify_percent;
  // A part within the area tolerance but of another size than the one
  // taught (seen at a slant, nearer the camera, at the lens's edge) is
  // verified at its own size where it does not verify at the taught one,
  // and its hands compared there as the unrefined candidates are: a mirror
  // image that verifies about as well (or alone) leaves the region out.
  const double scale = std::sqrt(r.area / body.area);
  if (direct.score * 100 < model.verify_percent && std::abs(scale - 1) > kMinScaledVerify) {
    std::vector<BoundarySample> sized = model.samples;
    for (auto& sample : sized) sample.point *= scale;
    const Best at_size = bestOf(direct_turns, model, sized, r.centroid, edges, false);
    const bool fits = at_size.score * 100 >= model.verify_percent;
    const Best mirror = body.mirror_symmetric
                            ? Best{}
                            : bestCandidate(mirror_turns, model, sized, r.centroid, edges, true);
    if (fits && mirror.score < at_size.score - kScaledMirrorMargin) {
      v.score = at_size.score;
      v.angle_deg = at_size.angle_deg;
      v.measured = at_size.score * 100;
      v.test = RegionTest::kPasses;
      return v;
    }
    if (mirror.score * 100 >= model.verify_percent) {
      v.test = RegionTest::kMirror;
      v.score = at_size.score;
      v.measured = mirror.score * 100;
      v.low = v.high = std::max(0.0, at_size.score) * 100;
      return v;
    }
  }
  v.score = direct.score;
  v.angle_deg = direct.angle_deg;
  v.measured = std::max(0.0, direct.score) * 100;
  const bool verified = direct.score * 100 >= model.verify_percent;
  if (body.mirror_symmetric) {
    v.test = verified ? RegionTest::kPasses : RegionTest::kVerify;
    return v;
  }
  // The mirror image of the model, turned its own way, at its best pose:
  // where the two hands differ decides which one the region is. A region
  // the model does not verify on is its mirror image when that verifies
  // at one of its candidates (an L's, whose legs swap sides): a whole
  // part, not a blob to search. Unrefined: a region of another type that
  // passes this one's body tests costs a few lookups more, not a search.
  const Best mirror =
      verified ? bestOf(mirror_turns, model, model.samples, r.centroid, edges, true)
               : bestCandidate(mirror_turns, model, model.samples, r.centroid, edges, true);
  if (verified ? showsMirrorImage(model, {r.centroid, direct.fit_deg, false},
                                  {r.centroid, mirror.fit_deg, true}, edges)
               : mirror.score * 100 >= model.verify_percent) {
    v.test = RegionTest::kMirror;
    v.measured = std::max(0.0, mirror.score) * 100;
    v.low = v.high = std::max(0.0, direct.score) * 100;
    return v;
  }
  v.test = verified ? RegionTest::kPasses : RegionTest::kVerify;
  return v;
}

}  // namespace picksight::vision
