// Sub-pixel pose refinement of parts on the grey-level edges of their
// region (the 0.5 crossing of its coverage), and the snapping of a trained
// model's boundary onto the edges it was fitted to.
#include "picksight/vision/blob_search/touching_parts.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include "picksight/common/angles.hpp"
#include "touching_parts_internal.hpp"

namespace picksight::vision {
namespace touching {

double loopOrientation(const BoundaryLoop& loop) {
  // The integral of x dy - y dx around the loop: along each primitive in
  // closed form (an arc's is cx dy - cy dx + r^2 sweep, no points on it to
  // place), then along the chord to the next one's start.
  const auto& prims = loop.primitives;
  double a = 0;
  for (size_t i = 0; i < prims.size(); ++i) {
    const Primitive& p = prims[i];
    const cv::Point2d s = p.pointAt(0);
    const cv::Point2d e = p.pointAt(1);
    if (p.kind == PrimitiveKind::kArc) {
      a += p.centre.x * (e.y - s.y) - p.centre.y * (e.x - s.x) +
           p.radius * p.radius * p.sweep_deg * kRadPerDeg;
    } else {
      a += s.x * e.y - e.x * s.y;
    }
    const cv::Point2d next = prims[(i + 1) % prims.size()].pointAt(0);
    a += e.x * next.y - next.x * e.y;
  }
  return a;
}

namespace {
// Step of the coverage readings along an edge sample's normal.
constexpr double kFitStepPx = 0.5;
// Edge-fit iterations before the last two read every third edge sample:
// the pose is still settling there.
constexpr int kSparseFitStride = 3;
// A sparse iteration that moves the boundary by less than this (pixels, at
// the rim) has settled: the remaining sparse ones are skipped.
constexpr double kSettledPx = 0.01;
// An edge crossing this close to the fitted boundary is one the pose
// explains: a right model's visible boundary lies within a few tenths of a
// pixel of its edges, and a primitive deviates from them by up to the
// conformity (1 px), a similar outline of another type by more.
constexpr double kPreciseEdgePx = 1.0;
// Edge samples this close to a primitive's end see the neighbouring edge.
constexpr double kCornerClearancePx = 2.0;
// See refinePoseOnEdges: the turn's ridge, relative to the shift's terms.
constexpr double kTurnRidge = 1e-6;
// How far either side of a primitive its teach image's edge is looked for
// (measureEdgeOffsets): the conformity it was fitted within, and the blur.
constexpr double kOffsetSearchPx = 1.5;

using picksight::normalizeDeg;

// The unit normal of primitive `p` at `t`, pointing away from the body: out
// of the outer loop, into a hole.
cv::Point2d awayNormal(const Primitive& p, double t, bool left_interior, bool hole) {
  cv::Point2d tangent;
  if (p.kind == PrimitiveKind::kLine) {
    tangent = (p.end - p.start) / std::max(p.length(), 1e-9);
  } else {
    const double a = angleOf(p.start - p.centre) * kRadPerDeg + t * p.sweep_deg * kRadPerDeg;
    const cv::Point2d r(std::cos(a), std::sin(a));
    tangent = p.sweep_deg >= 0 ? cv::Point2d(-r.y, r.x) : cv::Point2d(r.y, -r.x);
  }
  const cv::Point2d left(-tangent.y, tangent.x);
  const cv::Point2d interior = left_interior ? left : -left;
  return hole ? interior : -interior;
}

// Calls f(t, weight) every `step` pixels along primitive `p`, away from
// its ends where a normal sees the neighbouring edge (unless the primitive
// is a whole loop: a circle).
template <typename F>
void alongPrimitive(const Primitive& p, bool whole_loop, double weight, double step, F&& f) {
  const double length = p.length();
  const int count = std::max(1, static_cast<int>(std::floor(length / step)));
  for (int i = 0; i < count; ++i) {
    const double t = (i + 0.5) / count;
    const double along = t * length;
    if (!whole_loop && (along < kCornerClearancePx || length - along < kCornerClearancePx))
      continue;
    f(t, weight * p.weight * length / count);
  }
}

// Where, along p + s n (n pointing away from the body), the coverage falls
// through 0.5 from a clean inside to a clean outside, nearest to `expected`;
// none where the part touches another (no outside) or the edge is a mess.
// Read every `step` pixels from -window to window; `halve`: the chosen
// crossing is then placed between readings half a step apart (one more
// reading), as precisely as a scan at half the step would place it.
// The readings are taken outward from `expected`, interval by interval,
// and stop once no interval left can hold a nearer crossing: once the pose
// has settled the edge is within a reading or two of where it is expected,
// and most of the window is never read.
std::optional<double> edgeCrossing(const Coverage& cov, cv::Point2d p, cv::Point2d n, double window,
                                   double expected, double step, bool halve = false) {
  // The readings taken so far, on the stack: a window wider than they can
  // hold (the fits use 17 and 21 readings) is narrowed to them, about p.
  constexpr int kMaxReadings = 64;
  window = std::min(window, 0.5 * (kMaxReadings - 1) * step);
  const double span = (2 * window + 1e-9) / step;  // in steps; tested before conversion
  if (!(span >= 1)) return std::nullopt;
  const int readings = static_cast<int>(std::floor(span)) + 1;
  std::array<float, kMaxReadings> value;
  std::array<bool, kMaxReadings> read{};
  const auto reading = [&](int k) {
    if (!read[k]) {
      value[k] = cov.at(p + n * (-window + k * step));
      read[k] = true;
    }
    return value[k];
  };
  // The interval (k - 1, k) nearest to `expected` first, then outward on
  // both sides by the distance of their near ends (each side's next one
  // worked out once, when its turn comes).
  const int intervals = readings - 1;
  const double from = (expected + window) / step;  // `expected` in readings
  int below = std::clamp(static_cast<int>(std::floor(from)) + 1, 1, intervals);
  int above = below + 1;
  const auto nearEnd = [&](int k) {
    const double lo = -window + (k - 1) * step;
    const double hi = lo + step;
    return expected < lo ? lo - expected : expected > hi ? expected - hi : 0.0;
  };
  constexpr double kNone = std::numeric_limits<double>::infinity();
  double below_near = nearEnd(below);
  double above_near = above <= intervals ? nearEnd(above) : kNone;
  std::optional<double> best;
  double best_d = kNone;  // |*best - expected|
  int best_k = 0;
  while (below_near != kNone || above_near != kNone) {
    int k;
    double near;
    if (below_near <= above_near) {
      k = below;
      near = below_near;
      below_near = --below >= 1 ? nearEnd(below) : kNone;
    } else {
      k = above;
      near = above_near;
      above_near = ++above <= intervals ? nearEnd(above) : kNone;
    }
    // The intervals come nearest first: none left can do better.
    if (near > best_d) break;
    const double previous = reading(k - 1);
    if (!(previous >= 0.5)) continue;
    const double v = reading(k);
    if (!(v < 0.5)) continue;
    const double s = -window + k * step;
    const double at = s - step + step * (previous - 0.5) / (previous - v);
    const double d = std::abs(at - expected);
    // Equally near: the lower one, as a scan from -window would keep.
    if (d > best_d || (d == best_d && k > best_k)) continue;
    if (cov.at(p + n * (at - 1.5)) >= 0.7 && cov.at(p + n * (at + 1.5)) <= 0.3) {
      best = at;
      best_d = d;
      best_k = k;
    }
  }
  if (!best || !halve) return best;
  const double best_from = -window + (best_k - 1) * step;
  const double best_before = value[best_k - 1];
  const double best_after = value[best_k];
  const double half = 0.5 * step;
  const double middle = cov.at(p + n * (best_from + half));
  if (middle >= 0.5) return best_from + half + half * (middle - 0.5) / (middle - best_after);
  return best_from + half * (best_before - 0.5) / (best_before - middle);
}
}  // namespace

std::vector<EdgeSample> edgeSamples(const PartModel& model, double step) {
  std::vector<EdgeSample> out;
  for (const auto& loop : model.loops) {
    const bool left_interior = loopOrientation(loop) > 0;
    for (const auto& p : loop.primitives) {
      alongPrimitive(p, loop.primitives.size() == 1, loop.weight, step, [&](double t, double w) {
        out.push_back(
            {p.pointAt(t), awayNormal(p, t, left_interior, loop.hole), w, p.edgeOffsetAt(t)});
      });
    }
  }
  return out;
}

}  // namespace touching

using namespace touching;

EdgeFit refinePoseOnEdges(const PartModel& model, const Region& region, const ImagePose& start,
                          double search_px, int iterations,
                          const std::function<bool(const ImagePose&)>& worth_finishing) {
  const auto search = searchOf(model);
  const auto& samples = search->edges;
  const Coverage cov(region);
  const double flip = start.mirrored ? -1.0 : 1.0;
  EdgeFit fit;
  fit.pose = start;
  double offset = 0;
  double window = search_px;
  double gate = search_px;
  double total = 0;
  for (const auto& e : samples) total += e.weight;
  if (total <= 0) return fit;
  for (int it = 0; it < iterations; ++it) {
    const double c = std::cos(fit.pose.angle_deg * kRadPerDeg);
    const double s = std::sin(fit.pose.angle_deg * kRadPerDeg);
    // Coarse readings place the crossing well enough while the pose
    // settles; the two dense passes halve them.
    const bool dense = it >= iterations - 2;
    if (it == iterations - 2 && worth_finishing && !worth_finishing(fit.pose)) return fit;
    cv::Matx44d a = cv::Matx44d::zeros();
    cv::Vec4d b(0, 0, 0, 0);
    double found = 0;
    double precise = 0;
    double sum2 = 0;
    int used = 0;
    const size_t stride = it == iterations - 1 ? 1 : dense ? 2 : kSparseFitStride;
    for (size_t i = 0; i < samples.size(); i += stride) {
      const EdgeSample& e = samples[i];
      const cv::Point2d r = rotate({e.point.x, flip * e.point.y}, c, s);
      const cv::Point2d n = rotate({e.normal.x, flip * e.normal.y}, c, s);
      // Where the teach image's edge lay: off the primitive by e.offset.
      const double expected = offset + e.offset;
      const auto crossing =
          edgeCrossing(cov, fit.pose.centre + r, n, window, expected, kFitStepPx, dense);
      if (!crossing || std::abs(*crossing - expected) > gate) continue;
      const double residual = *crossing - expected;
      found += e.weight;
      if (std::abs(residual) <= kPreciseEdgePx) precise += e.weight;
      sum2 += residual * residual;
      ++used;
      const cv::Vec4d j(n.x, n.y, n.x * -r.y + n.y * r.x, 1.0);
      a += e.weight * (j * j.t());
      b += e.weight * (*crossing - e.offset) * j;
    }
    if (used < 8) return fit;
    // Measured before the last update: it moves the pose by hundredths of a
    // pixel, not worth another pass over every sample.
    const double rms = std::sqrt(sum2 / used);
    fit.rms_px = rms;
    fit.inlier_fraction = found * static_cast<double>(stride) / total;
    fit.precise_length = precise * static_cast<double>(stride);
    // A disc's boundary says nothing of its turn (every normal runs through
    // the centre: the turn's column is zero) and the system was singular:
    // no disc was ever placed in a blob (20 touching discs of a photograph,
    // none found). A ridge a millionth of the shift's terms, at the part's
    // radius, keeps the turn where it is then, and changes no other fit.
    const double reach = std::max(model.radius, 1.0);
    a(2, 2) += kTurnRidge * (a(0, 0) + a(1, 1)) * reach * reach;
    cv::Vec4d x;
    if (!cv::solve(a, b, x, cv::DECOMP_CHOLESKY)) return fit;
    fit.pose.centre += cv::Point2d(x[0], x[1]);
    fit.pose.angle_deg = normalizeDeg(fit.pose.angle_deg + x[2] / kRadPerDeg);
    offset = x[3];
    // Narrow the search as the pose settles; outliers (the other part's
    // edges near a contact) fall outside the gate.
    window = std::max(1.5, std::min(window, 3.0 * rms + 1.0));
    gate = std::max(0.5, std::min(gate, 3.0 * rms + 0.3));
    // Settled on the sparse samples: straight on to the dense passes.
    const double moved = std::hypot(x[0], x[1]) + std::abs(x[2]) * model.radius;
    if (moved < kSettledPx && it < iterations - 3) it = iterations - 3;
  }
  fit.ok = true;
  return fit;
}

namespace touching {
std::vector<double> bridgedOffsets(const std::vector<std::optional<double>>& crossings) {
  const size_t n = crossings.size();
  std::vector<double> out(n, 0.0);
  size_t first = 0;
  while (first < n && !crossings[first]) ++first;
  if (first == n) return out;  // none read: the boundary as it is
  // Once round the loop from the first crossing: each crossing kept, and
  // the gap before it (from the crossing before, over the loop's start
  // too; a lone crossing is its own) a straight run between the two.
  size_t a = first;
  for (size_t step = 1; step <= n; ++step) {
    const size_t b = (first + step) % n;
    if (!crossings[b]) continue;
    const size_t gap = (b + n - a - 1) % n + 1;  // steps from a to b
    for (size_t s = 1; s < gap; ++s) {
      const size_t k = (a + s) % n;
      const double da = static_cast<double>(s);
      const double db = static_cast<double>(gap - s);
      out[k] = (*crossings[a] * db + *crossings[b] * da) / (da + db);
    }
    out[b] = *crossings[b];
    a = b;
  }
  return out;
}
}  // namespace touching

std::optional<cv::Point2d> outlineCentroid(const PartModel& model, const Region& region,
                                           const ImagePose& pose, double search_px) {
  const Coverage cov(region);
  const double flip = pose.mirrored ? -1.0 : 1.0;
  const double c = std::cos(pose.angle_deg * kRadPerDeg);
  const double s = std::sin(pose.angle_deg * kRadPerDeg);
  double area = 0;
  cv::Point2d first(0, 0);
  for (const auto& loop : model.loops) {
    const bool left_interior = loopOrientation(loop) > 0;
    // Every kFitStepPx along each primitive, to its ends (the polygon must
    // close round corners too): where the edge crosses, and where it does
    // not cleanly, the boundary moved by the crossings either side (about
    // the pose's centre).
    std::vector<cv::Point2d> points;
    std::vector<cv::Point2d> normals;
    std::vector<std::optional<double>> crossings;
    for (const auto& p : loop.primitives) {
      const double length = p.length();
      const int count = std::max(1, static_cast<int>(std::ceil(length / kFitStepPx)));
      for (int i = 0; i < count; ++i) {
        const double t = static_cast<double>(i) / count;
        const cv::Point2d m = p.pointAt(t);
        const cv::Point2d a = awayNormal(p, t, left_interior, loop.hole);
        points.push_back(rotate({m.x, flip * m.y}, c, s));
        normals.push_back(rotate({a.x, flip * a.y}, c, s));
        crossings.push_back(edgeCrossing(cov, pose.centre + points.back(), normals.back(),
                                         search_px, 0.0, 0.25, true));
      }
    }
    const std::vector<double> along = bridgedOffsets(crossings);
    for (size_t i = 0; i < points.size(); ++i) points[i] += normals[i] * along[i];
    // The polygon's area and first moments (the shoelace sums, twice the
    // area and six times the moments), counted positive for the outer loop
    // and negative for holes whichever way round they run.
    double la = 0;
    cv::Point2d lf(0, 0);
    for (size_t i = 0; i < points.size(); ++i) {
      const cv::Point2d& a = points[i];
      const cv::Point2d& b = points[(i + 1) % points.size()];
      const double cross = a.x * b.y - b.x * a.y;
      la += cross;
      lf += (a + b) * cross;
    }
    const double sign = (la < 0 ? -1.0 : 1.0) * (loop.hole ? -1.0 : 1.0);
    area += sign * la;
    first += sign * lf;
  }
  if (!(area > 0)) return std::nullopt;
  return pose.centre + first / (3.0 * area);
}

void snapToEdges(std::vector<BoundaryLoop>& loops, const Region& region, cv::Point2d origin) {
  const Coverage cov(region);
  for (auto& loop : loops) {
    const bool left_interior = loopOrientation(loop) > 0;
    for (auto& p : loop.primitives) {
      std::vector<cv::Point2d> edge;
      alongPrimitive(p, loop.primitives.size() == 1, 1.0, 1.0, [&](double t, double) {
        const cv::Point2d at = p.pointAt(t) + origin;
        const cv::Point2d n = awayNormal(p, t, left_interior, loop.hole);
        if (const auto s = edgeCrossing(cov, at, n, 2.5, 0.0, 0.25)) edge.push_back(at + n * *s);
      });
      Primitive snapped = p;
      if (p.kind == PrimitiveKind::kLine) {
        if (edge.size() < 4) continue;
        cv::Vec4f line;
        std::vector<cv::Point2f> pts(edge.begin(), edge.end());
        cv::fitLine(pts, line, cv::DIST_L2, 0, 0.01, 0.01);
        const cv::Point2d d(line[0], line[1]);
        const cv::Point2d c = cv::Point2d(line[2], line[3]) - origin;
        snapped.start = c + d * (p.start - c).dot(d);
        snapped.end = c + d * (p.end - c).dot(d);
      } else {
        if (edge.size() < 6) continue;
        // Kasa fit: x^2 + y^2 + D x + E y + F = 0, about the points' mean.
        cv::Point2d mean(0, 0);
        for (const auto& q : edge) mean += q;
        mean /= static_cast<double>(edge.size());
        cv::Matx33d a = cv::Matx33d::zeros();
        cv::Vec3d rhs(0, 0, 0);
        for (const auto& q : edge) {
          const cv::Point2d d = q - mean;
          const cv::Vec3d v(d.x, d.y, 1.0);
          a += v * v.t();
          rhs += v * -(d.x * d.x + d.y * d.y);
        }
        cv::Vec3d x;
        if (!cv::solve(a, rhs, x, cv::DECOMP_LU)) continue;
        const double r2 = 0.25 * (x[0] * x[0] + x[1] * x[1]) - x[2];
        if (!(r2 > 0)) continue;
        const double radius = std::sqrt(r2);
        // A short arc's circle is poorly determined: keep the old one then.
        if (std::abs(radius - p.radius) > 1.5) continue;
        const cv::Point2d centre = mean + cv::Point2d(-0.5 * x[0], -0.5 * x[1]) - origin;
        const auto onCircle = [&](cv::Point2d q) {
          const cv::Point2d d = q - centre;
          const double n = std::hypot(d.x, d.y);
          return n > 0 ? centre + d * (radius / n) : q;
        };
        snapped.centre = centre;
        snapped.radius = radius;
        snapped.start = onCircle(p.start);
        snapped.end = onCircle(p.end);
      }
      // A circle through a short arc's few edge crossings may fit with its
      // centre across the arc's chord: the arc, walked from its start the
      // same way round, then runs round the far side of that circle, off
      // the part (16.8 px at its middle on a Tari-1000 outline 120 px
      // long). The old arc stays then.
      if (p.kind == PrimitiveKind::kArc) {
        const cv::Point2d chord = p.end - p.start;
        const auto side = [&](cv::Point2d centre) {
          const cv::Point2d to = centre - p.start;
          return chord.x * to.y - chord.y * to.x;
        };
        if (side(p.centre) * side(snapped.centre) < 0) continue;
      }
      p = snapped;
    }
  }
}

void measureEdgeOffsets(std::vector<BoundaryLoop>& loops, const Region& region, cv::Point2d origin,
                        int turns) {
  const Coverage cov(region);
  // The model turned by each of the part's symmetric turns about the
  // origin (its centre of symmetry).
  std::vector<std::pair<double, double>> cs;
  for (int j = 0; j < std::max(turns, 1); ++j) {
    const double a = 2 * M_PI * j / std::max(turns, 1);
    cs.emplace_back(std::cos(a), std::sin(a));
  }
  for (auto& loop : loops) {
    const bool left_interior = loopOrientation(loop) > 0;
    // Read round the loop in order, so that a stretch without a crossing
    // is bridged from the crossings either side (bridgedOffsets).
    std::vector<std::optional<double>> crossings;
    for (const auto& p : loop.primitives) {
      const int count = edgeOffsetCount(p.length());
      for (int k = 0; k < count; ++k) {
        const double t = (k + 0.5) / count;
        const cv::Point2d at = p.pointAt(t);
        const cv::Point2d n = awayNormal(p, t, left_interior, loop.hole);
        double sum = 0;
        int found = 0;
        for (const auto& [c, s] : cs) {
          const auto x = edgeCrossing(cov, origin + rotate(at, c, s), rotate(n, c, s),
                                      kOffsetSearchPx, 0.0, 0.25, true);
          if (!x) continue;
          sum += *x;
          ++found;
        }
        crossings.push_back(found > 0 ? std::optional<double>(sum / found) : std::nullopt);
      }
    }
    const std::vector<double> along = bridgedOffsets(crossings);
    size_t next = 0;
    for (auto& p : loop.primitives) {
      const int count = edgeOffsetCount(p.length());
      p.edge_offsets_mpx.resize(static_cast<size_t>(count));
      for (auto& o : p.edge_offsets_mpx) o = edgeOffsetMpx(along[next++]);
    }
  }
}

}  // namespace picksight::vision
