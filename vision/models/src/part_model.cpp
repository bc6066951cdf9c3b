// Part models: the Hu distance with its floors, which hand a region shows
// (the boundary where the two hands lie apart), how far a model is from its
// mirror image, and the check of a model's values.
#include "picksight/vision/models/part_model.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "picksight/common/angles.hpp"
#include "picksight/common/text.hpp"

namespace picksight::vision {
namespace {
// How much a model sample at `separation` pixels from the other hand's
// boundary tells the two apart: nothing within the edge tolerance (both
// would verify there), fully from twice the tolerance.
double handednessWeight(double separation, double tolerance) {
  return std::clamp((separation - tolerance) / tolerance, 0.0, 1.0);
}

// What one hand (the model, or its mirror image) placed at `pose` shows on
// the region's edges where the other hand, placed at `other`, lies apart
// from it.
struct HandEvidence {
  double weight = 0;    // of the samples that tell the hands apart
  double on = 0;        // of those, within the tolerance of an edge
  double distance = 0;  // weighted sum of their clipped edge distances
};

HandEvidence handEvidence(const PartModel& m, const ImagePose& pose, const ImagePose& other,
                          const EdgeDistance& edges) {
  const double c = std::cos(pose.angle_deg * kRadPerDeg);
  const double s = std::sin(pose.angle_deg * kRadPerDeg);
  const double oc = std::cos(other.angle_deg * kRadPerDeg);
  const double os = std::sin(other.angle_deg * kRadPerDeg);
  const double clip = 2 * m.edge_tolerance;
  // A map built for a smaller tolerance than the model's now cannot say.
  const BoundaryDistanceMap* map =
      m.boundary_map && m.boundary_map->reach() >= clip ? m.boundary_map.get() : nullptr;
  HandEvidence e;
  PrimitiveIndex nearest;
  for (const auto& sample : m.samples) {
    const double py = pose.mirrored ? -sample.point.y : sample.point.y;
    const cv::Point2d x =
        pose.centre + cv::Point2d(c * sample.point.x - s * py, s * sample.point.x + c * py);
    // The same image point in the other hand's model frame.
    const cv::Point2d d = x - other.centre;
    cv::Point2d u(oc * d.x + os * d.y, -os * d.x + oc * d.y);
    if (other.mirrored) u.y = -u.y;
    const double separation = map ? map->at(u) : boundaryDistance(m.loops, u, &nearest);
    const double w = sample.weight * handednessWeight(separation, m.edge_tolerance);
    if (w <= 0) continue;
    const double at = edges.at(x);
    e.weight += w;
    if (at <= m.edge_tolerance) e.on += w;
    e.distance += w * std::min<double>(at, clip);
  }
  return e;
}

// Invariants 2 to 6 are powers of how far a part departs from a disc: its
// ellipticity squared (H2), its skew squared (H3, H4), higher products of
// the two (H5, H6). Compared as plain logs, a near-round part's tiny values
// weigh as much as a long part's large ones: in a photograph of sweets
// taught from one, the other lone sweets lay 1.8-3.6 apart (tolerance 1.35),
// and a washer taught 1 % out of round lost 4 of 5 pieces 0-4.5 % out of
// round, while all are discs to anyone. Below a floor (a deviation of
// kHuFloorShare of the part's own second moment, H1, in each moment the
// invariant is made of) an invariant is taken for "round enough":
// log10(1 + |h| / floor) is 0 there and log10|h| less a constant above it,
// where the distance is the plain one. Both sides of a comparison take the
// model's floors.
constexpr double kHuFloorShare = 0.1;
// Degree of H2..H6 in the second-order (a) and third-order (b) normalized
// moments, which scale as H1 and H1^1.5 (H1 itself is compared as it is).
constexpr std::array<std::pair<int, int>, 5> kHuDegrees = {
    {{2, 0}, {0, 2}, {0, 2}, {0, 4}, {1, 2}}};

// The floors of H2..H6 (at 1..5) for a part whose H1 is `h1`.
std::array<double, 6> huFloors(double h1) {
  const double second = kHuFloorShare * h1;                 // a second-order moment's
  const double third = kHuFloorShare * h1 * std::sqrt(h1);  // a third-order one's
  std::array<double, 6> floors{};
  for (size_t i = 1; i < floors.size(); ++i) {
    floors[i] = 1;
    const auto [a, b] = kHuDegrees[i - 1];
    for (int k = 0; k < a; ++k) floors[i] *= second;
    for (int k = 0; k < b; ++k) floors[i] *= third;
  }
  return floors;
}

double flooredLog(double log_h, size_t i, double floor) {
  if (i == 0) return log_h;
  // logHu writes 0 for an invariant that is exactly 0 (a square's H2).
  if (log_h == 0) return 0;
  // H2..H4 are sums of squares (positive, any size: their log inverts
  // exactly); H5 and H6 carry a sign and stay below 1 in magnitude.
  const bool positive = i <= 3;
  const double value = std::log10(1 + std::pow(10.0, positive ? -log_h : -std::abs(log_h)) / floor);
  return positive || log_h > 0 ? value : -value;
}
}  // namespace

// The weighted boundary length of the model that lies apart from its
// mirror image turned by `turn_deg`: sample p against the set R(t) M P, i.e.
// M R(-t) p against P (M: y -> -y).
double chiralLength(const PartModel& m, double turn_deg) {
  const double c = std::cos(turn_deg * kRadPerDeg);
  const double s = std::sin(turn_deg * kRadPerDeg);
  double length = 0;
  PrimitiveIndex nearest;
  for (const auto& sample : m.samples) {
    const cv::Point2d p = sample.point;
    const cv::Point2d u(c * p.x + s * p.y, -(-s * p.x + c * p.y));
    length +=
        sample.weight * handednessWeight(boundaryDistance(m.loops, u, &nearest), m.edge_tolerance);
  }
  return length;
}

double huDistance(const BodyModel& body, const HuArray& log_hu) {
  const auto floors = huFloors(std::pow(10.0, -body.log_hu[0]));
  double d = 0;
  // Not the 7th invariant: the only one a mirror changes (its sign), and on
  // a nearly mirror-symmetric part so small that lighting and resampling
  // set its sign. Which hand a region shows is decided on its boundary
  // (showsMirrorImage).
  for (size_t i = 0; i + 1 < log_hu.size(); ++i) {
    if (body.hu_used[i])
      d += std::abs(flooredLog(body.log_hu[i], i, floors[i]) - flooredLog(log_hu[i], i, floors[i]));
  }
  return d;
}

double reportedTurnDeg(const PartModel& model, double turn_deg) {
  return centredDeg(turn_deg, model.symmetryDeg());
}

const char* errorName(PartModelErrc e) {
  switch (e) {
    case PartModelErrc::kNotGrey:
      return "not grey";
    case PartModelErrc::kNoPart:
      return "no part";
    case PartModelErrc::kSeveralParts:
      return "several parts";
    case PartModelErrc::kInvalid:
      return "invalid";
  }
  return "unknown";
}

namespace {
// What is wrong with a model; empty when nothing is.
std::string modelProblem(const PartModel& m) {
  const auto finite = [](double v) { return std::isfinite(v); };
  if (m.type < 0 || m.type > 9999) return "type must be in [0, 9999]";
  if (!finite(m.body.area) || m.body.area <= 0) return "body area must be a positive number";
  if (!finite(m.body.area_tolerance) || m.body.area_tolerance <= 0 || m.body.area_tolerance >= 1) {
    return "area tolerance must be in (0, 1)";
  }
  if (m.body.holes < 0 || m.body.holes > 10000) return "hole count out of range";
  if (m.colour) {
    for (int c = 0; c < 3; ++c) {
      for (const double v : {m.colour->part[c], m.colour->background[c]}) {
        if (!finite(v) || v < 0 || v > 255) return "colour levels must be in [0, 255]";
      }
    }
    if (cv::norm(m.colour->part - m.colour->background) <= 0) {
      return "the part's colour must differ from its surface's";
    }
  }
  if (!finite(m.min_region_area) || m.min_region_area < 0 || !finite(m.min_hole_area) ||
      m.min_hole_area < 0) {
    return "minimum region and hole areas must be numbers >= 0";
  }
  for (double h : m.body.log_hu) {
    if (!finite(h)) return "log Hu invariants must be finite";
  }
  if (!finite(m.body.hu_tolerance) || m.body.hu_tolerance <= 0)
    return "Hu tolerance must be positive";
  if (m.orientation_order < 0 || m.orientation_order > kMaxModelOrder)
    return "orientation order out of range";
  if (!finite(m.orientation_phase_deg)) return "orientation phase must be finite";
  if (m.symmetry_order < 0 || m.symmetry_order > kMaxModelOrder)
    return "symmetry order out of range";
  if (!finite(m.conformity) || m.conformity <= 0 || m.conformity > 50)
    return "conformity must be in (0, 50] px";
  if (!finite(m.edge_tolerance) || m.edge_tolerance <= 0 || m.edge_tolerance > 50) {
    return "edge tolerance must be in (0, 50] px";
  }
  if (!finite(m.verify_percent) || m.verify_percent <= 0 || m.verify_percent > 100) {
    return "verify percent must be in (0, 100]";
  }
  if (m.views.size() > kMaxModelViews)
    return "at most " + std::to_string(kMaxModelViews) + " views beyond the teach image";
  for (const auto& v : m.views) {
    if (!finite(v.x) || !finite(v.y) || std::hypot(v.x, v.y) > kMaxViewReadingPx)
      return "a view's centroid must lie within " + formatFixed(kMaxViewReadingPx, 1) +
             " px of the teach image's";
  }
  if (!finite(m.origin_shift.x) || !finite(m.origin_shift.y) ||
      std::hypot(m.origin_shift.x, m.origin_shift.y) > kMaxOriginShiftPx)
    return "the origin must lie within " + formatFixed(kMaxOriginShiftPx, 1) +
           " px of the teach image's centroid";
  if (cv::norm(m.origin_shift - originFromViews(m.views)) > 1e-9)
    return "the origin must be the median of the views' centroids";
  if (!m.views.empty() && m.symmetry_order != 1)
    return "views move the origin of a part without rotational symmetry only";
  if (m.loops.empty() || m.loops[0].hole) return "the boundary needs an outer loop first";
  for (const auto& loop : m.loops) {
    if (loop.primitives.empty()) return "a boundary loop has no primitives";
    if (!finite(loop.weight) || loop.weight < 0) return "loop weights must be >= 0";
    for (const auto& p : loop.primitives) {
      if (!finite(p.start.x) || !finite(p.start.y) || !finite(p.end.x) || !finite(p.end.y) ||
          !finite(p.weight) || p.weight < 0) {
        return "a primitive has a bad point or weight";
      }
      if (p.kind == PrimitiveKind::kArc &&
          (!finite(p.radius) || p.radius <= 0 || !finite(p.sweep_deg) ||
           std::abs(p.sweep_deg) > 360 || !finite(p.centre.x) || !finite(p.centre.y))) {
        return "an arc has a bad centre, radius or sweep";
      }
      // About one a pixel of its length: a length a hair under a whole
      // number of pixels when taught may be a hair over after the turns
      // and shifts that centre the model and views make.
      const auto& o = p.edge_offsets_mpx;
      const int count = edgeOffsetCount(p.length());
      if (!o.empty() && std::abs(static_cast<int>(o.size()) - count) > 1)
        return "a primitive of " + formatFixed(p.length(), 1) + " px holds " +
               std::to_string(count) + " edge offsets (one a pixel), not " +
               std::to_string(o.size());
      const int16_t bound = edgeOffsetMpx(kMaxEdgeOffsetPx);
      if (std::any_of(o.begin(), o.end(), [&](int16_t v) { return v < -bound || v > bound; }))
        return "edge offsets must lie within " + formatFixed(kMaxEdgeOffsetPx, 1) + " px";
      const auto& w = p.edge_weights_pct;
      if (!w.empty() && std::abs(static_cast<int>(w.size()) - count) > 1)
        return "a primitive of " + formatFixed(p.length(), 1) + " px holds " +
               std::to_string(count) + " edge weights (one a pixel), not " +
               std::to_string(w.size());
      if (std::any_of(w.begin(), w.end(), [](uint8_t v) { return v > 100; }))
        return "edge weights are whole percents, 0 to 100";
    }
  }
  return {};
}

}  // namespace

bool showsMirrorImage(const PartModel& model, const ImagePose& direct, const ImagePose& mirror,
                      const EdgeDistance& edges) {
  const HandEvidence d = handEvidence(model, direct, mirror, edges);
  const HandEvidence m = handEvidence(model, mirror, direct, edges);
  // Placed this way the two hands coincide: nothing shows it is the model.
  if (d.weight <= 0 || m.weight <= 0) return true;
  const double on_direct = d.on / d.weight;
  const double on_mirror = m.on / m.weight;
  if (std::abs(on_direct - on_mirror) > 1e-9) return on_mirror > on_direct;
  return m.distance / m.weight <= d.distance / d.weight;
}

namespace {
// A stored symmetry order is checked as far off as the training image's
// edges may lie from the model's fitted boundary: training keeps an order
// when 97 % of the boundary, turned, lies within the edge tolerance
// (conformity + 1 px) of those edges, which lie within the conformity of
// the boundary; twice the training tolerance covers both with room for the
// pixel grid. Over 90 % of a part's boundary lies that close to itself
// turned by its symmetry; an L turned by a half turn, or a bar by a
// quarter, has a third of it or less.
constexpr double kMinSymmetryShare = 0.9;

// The share of the boundary's weight that, turned by `turn_deg`, lies
// within `reach` pixels of the boundary.
double turnedShare(const PartModel& m, double turn_deg, double reach) {
  const double c = std::cos(turn_deg * kRadPerDeg);
  const double s = std::sin(turn_deg * kRadPerDeg);
  double on = 0;
  double total = 0;
  PrimitiveIndex nearest;
  for (const auto& sample : m.samples) {
    const cv::Point2d p = sample.point;
    total += sample.weight;
    if (boundaryDistance(m.loops, {c * p.x - s * p.y, s * p.x + c * p.y}, &nearest) <= reach)
      on += sample.weight;
  }
  return total > 0 ? on / total : 0;
}
}  // namespace

Result<void> checkSymmetry(const PartModel& model) {
  if (model.symmetry_order == 1) return {};
  std::vector<double> turns;
  if (model.symmetry_order == 0) {
    for (int k = 1; k < 24; ++k) turns.push_back(15.0 * k);
  } else {
    turns.push_back(360.0 / model.symmetry_order);
  }
  const double reach = 2 * (model.conformity + 1.0);
  for (const double turn : turns) {
    const double share = turnedShare(model, turn, reach);
    if (share < kMinSymmetryShare) {
      char text[200];
      std::snprintf(text, sizeof text,
                    "symmetry order %d does not fit the boundary: turned by %.1f deg, %.0f %% of "
                    "it lies within %.1f px of itself (%.0f %% needed)",
                    model.symmetry_order, turn, 100 * share, reach, 100 * kMinSymmetryShare);
      return makeError(PartModelErrc::kInvalid, text);
    }
  }
  return {};
}

namespace {
// The median of `values` (reordered), the middle two's mean when even.
double middleOf(std::vector<double>& values) {
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}
}  // namespace

cv::Point2d originFromViews(const std::vector<cv::Point2d>& views) {
  if (views.empty()) return {0, 0};
  const auto median = [&](double cv::Point2d::*axis) {
    std::vector<double> v{0.0};  // the teach image's own reading
    for (const auto& p : views) v.push_back(p.*axis);
    return middleOf(v);
  };
  return {median(&cv::Point2d::x), median(&cv::Point2d::y)};
}

double viewSpread(const PartModel& model) {
  if (model.views.empty()) return 0;
  std::vector<double> distances{cv::norm(model.origin_shift)};  // the teach image's (0, 0)
  for (const auto& v : model.views) distances.push_back(cv::norm(v - model.origin_shift));
  return middleOf(distances);
}

Result<void> validateModel(const PartModel& model) {
  const std::string problem = modelProblem(model);
  if (problem.empty()) return {};
  return makeError(PartModelErrc::kInvalid, problem);
}

}  // namespace picksight::vision
