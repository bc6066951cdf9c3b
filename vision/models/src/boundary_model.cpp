// Boundary models: Douglas-Peucker polygon, arcs grown over runs of its
// segments, corners between primitives, boundary samples and distances.
#include "picksight/vision/models/boundary_model.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

#include "picksight/common/angles.hpp"

namespace picksight::vision {
namespace {
// An arc whose radius exceeds this many times the loop's extent is a line.
constexpr double kMaxRadiusFactor = 4.0;

double angleOf(cv::Point2d v) { return std::atan2(v.y, v.x) / kRadPerDeg; }

using picksight::kRadPerDeg;
using picksight::signedDeg;

cv::Point2d unit(cv::Point2d v) {
  const double n = std::hypot(v.x, v.y);
  return n > 0 ? v / n : cv::Point2d(1, 0);
}

double pointLineDistance(cv::Point2d p, cv::Point2d a, cv::Point2d b) {
  const cv::Point2d d = b - a;
  const double n = std::hypot(d.x, d.y);
  if (n == 0) return std::hypot(p.x - a.x, p.y - a.y);
  return std::abs(d.x * (p.y - a.y) - d.y * (p.x - a.x)) / n;
}

// Douglas-Peucker over the cyclic index range [a, b] of `pts` (b may exceed
// n: indices are taken modulo n); appends the split points strictly inside.
void douglasPeucker(const std::vector<cv::Point2d>& pts, size_t a, size_t b, double eps,
                    std::vector<size_t>& out) {
  const size_t n = pts.size();
  if (b <= a + 1) return;
  double worst = -1;
  size_t at = a;
  const cv::Point2d from = pts[a % n];
  const cv::Point2d d = pts[b % n] - from;
  const double length = std::hypot(d.x, d.y);
  if (length == 0) {
    for (size_t i = a + 1; i < b; ++i) {
      const double e = std::hypot(pts[i % n].x - from.x, pts[i % n].y - from.y);
      if (e > worst) {
        worst = e;
        at = i;
      }
    }
  } else {
    // The farthest point from the chord: the largest cross product, divided
    // by the chord's length once (this runs over every boundary pixel of
    // every blob). The index wraps by a comparison, not a division per
    // point (a division cost more than the rest of the loop).
    size_t wrapped = (a + 1) % n;
    for (size_t i = a + 1; i < b; ++i) {
      const cv::Point2d v = pts[wrapped] - from;
      if (++wrapped == n) wrapped = 0;
      const double e = std::abs(d.x * v.y - d.y * v.x);
      if (e > worst) {
        worst = e;
        at = i;
      }
    }
    worst /= length;
  }
  if (worst <= eps) return;
  douglasPeucker(pts, a, at, eps, out);
  out.push_back(at);
  douglasPeucker(pts, at, b, eps, out);
}

struct Circle {
  cv::Point2d centre;
  double radius = 0;
};

// Running sums of a closed contour's coordinates and their products up to
// the third order, over the contour walked twice (indices 0..2n), about a
// point near its middle: the sums over any stretch first..last in two
// reads, so that fitting circles to stretches that grow point by point
// costs the same at any length.
class ContourSums {
 public:
  explicit ContourSums(const std::vector<cv::Point2d>& pts) {
    cv::Point2d lo = pts.front();
    cv::Point2d hi = lo;
    for (const auto& p : pts) {
      lo = {std::min(lo.x, p.x), std::min(lo.y, p.y)};
      hi = {std::max(hi.x, p.x), std::max(hi.y, p.y)};
    }
    origin_ = 0.5 * (lo + hi);
    const size_t n = pts.size();
    sums_.resize(2 * n + 1);
    for (size_t i = 0; i < 2 * n; ++i) {
      const cv::Point2d& p = pts[i < n ? i : i - n];
      const double u = p.x - origin_.x;
      const double v = p.y - origin_.y;
      const Sums term{1, u, v, u * u, v * v, u * v, u * u * u, v * v * v, u * u * v, u * v * v};
      for (size_t k = 0; k < term.size(); ++k) sums_[i + 1][k] = sums_[i][k] + term[k];
    }
  }

  // Kasa fit over first..last (inclusive, first <= last < 2n).
  bool fitCircle(size_t first, size_t last, Circle* circle) const {
    if (last < first || last - first + 1 < 3) return false;
    Sums t;
    for (size_t k = 0; k < t.size(); ++k) t[k] = sums_[last + 1][k] - sums_[first][k];
    const double n = t[0];
    const double mu = t[1] / n;
    const double mv = t[2] / n;
    // Central sums (about the stretch's mean) from the raw ones.
    const double pp = t[3] - n * mu * mu;
    const double qq = t[4] - n * mv * mv;
    const double pq = t[5] - n * mu * mv;
    const double ppp = t[6] - 3 * mu * t[3] + 2 * n * mu * mu * mu;
    const double qqq = t[7] - 3 * mv * t[4] + 2 * n * mv * mv * mv;
    const double ppq = t[8] - 2 * mu * t[5] - mv * t[3] + 2 * n * mu * mu * mv;
    const double pqq = t[9] - 2 * mv * t[5] - mu * t[4] + 2 * n * mu * mv * mv;
    // x^2 + y^2 + D x + E y + F = 0 about the mean; its sums of x and y are 0.
    const cv::Matx33d a(pp, pq, 0, pq, qq, 0, 0, 0, n);
    const cv::Vec3d rhs(-(ppp + pqq), -(ppq + qqq), -(pp + qq));
    cv::Vec3d s;
    if (!cv::solve(a, rhs, s, cv::DECOMP_LU)) return false;
    const double r2 = 0.25 * (s[0] * s[0] + s[1] * s[1]) - s[2];
    if (!(r2 > 0)) return false;
    circle->centre = origin_ + cv::Point2d(mu - 0.5 * s[0], mv - 0.5 * s[1]);
    circle->radius = std::sqrt(r2);
    return true;
  }

 private:
  using Sums = std::array<double, 10>;
  cv::Point2d origin_;
  std::vector<Sums> sums_;
};

// Whether every point first..last lies within `limit` of the circle.
// A point whose squared distance from the centre lies well inside the band
// (by a relative margin far above hypot's rounding) is within without its
// square root; only those near the band's edges are measured as before, so
// the answer is the one the root gives. The index wraps by a comparison.
bool withinOfCircle(const std::vector<cv::Point2d>& pts, size_t first, size_t last, const Circle& c,
                    double limit) {
  const size_t n = pts.size();
  const double inner = std::max(0.0, c.radius - limit);
  const double surely_above = inner * inner * (1 + 1e-9);
  const double surely_below = (c.radius + limit) * (c.radius + limit) * (1 - 1e-9);
  size_t wrapped = first % n;
  for (size_t i = first; i <= last; ++i) {
    const cv::Point2d d = pts[wrapped] - c.centre;
    if (++wrapped == n) wrapped = 0;
    const double d2 = d.x * d.x + d.y * d.y;
    if (d2 > surely_above && d2 < surely_below) continue;
    if (std::abs(std::hypot(d.x, d.y) - c.radius) > limit) return false;
  }
  return true;
}

// Signed sweep of the arc through points first..last about `centre`.
double sweepOf(const std::vector<cv::Point2d>& pts, size_t first, size_t last, cv::Point2d centre) {
  double sweep = 0;
  double previous = angleOf(pts[first % pts.size()] - centre);
  for (size_t i = first + 1; i <= last; ++i) {
    const double a = angleOf(pts[i % pts.size()] - centre);
    sweep += signedDeg(a - previous);
    previous = a;
  }
  return sweep;
}

cv::Point2d onCircle(const Circle& c, cv::Point2d p) {
  return c.centre + unit(p - c.centre) * c.radius;
}

Primitive makeLine(cv::Point2d a, cv::Point2d b) {
  Primitive p;
  p.kind = PrimitiveKind::kLine;
  p.start = a;
  p.end = b;
  return p;
}
// The larger side of the points' bounding box.
double extentOf(const std::vector<cv::Point2d>& pts) {
  double x0 = pts[0].x, x1 = x0, y0 = pts[0].y, y1 = y0;
  for (const auto& p : pts) {
    x0 = std::min(x0, p.x);
    x1 = std::max(x1, p.x);
    y0 = std::min(y0, p.y);
    y1 = std::max(y1, p.y);
  }
  return std::max(x1 - x0, y1 - y0);
}

// The Douglas-Peucker polygon of a closed contour (`n` >= 4 points),
// started at its sharpest turn so that no arc runs through the start: its
// m vertices as unwrapped contour indices, increasing, and the first again
// plus n at the end (m + 1 in all).
std::vector<size_t> polygonFromSharpest(const std::vector<cv::Point2d>& pts, double conformity) {
  const size_t n = pts.size();
  // Polygon: split at the point farthest from the first, then recursively.
  size_t far = 0;
  double far_d = -1;
  for (size_t i = 0; i < n; ++i) {
    const double d = std::hypot(pts[i].x - pts[0].x, pts[i].y - pts[0].y);
    if (d > far_d) {
      far_d = d;
      far = i;
    }
  }
  std::vector<size_t> v{0};
  douglasPeucker(pts, 0, far, conformity, v);
  v.push_back(far);
  douglasPeucker(pts, far, n, conformity, v);
  const size_t m = v.size();

  // Arcs must not run through the start: begin at the sharpest turn.
  size_t start = 0;
  double sharpest = -1;
  for (size_t j = 0; j < m; ++j) {
    const cv::Point2d in = pts[v[j]] - pts[v[(j + m - 1) % m]];
    const cv::Point2d out_dir = pts[v[(j + 1) % m]] - pts[v[j]];
    const double turn = std::abs(signedDeg(angleOf(out_dir) - angleOf(in)));
    if (turn > sharpest) {
      sharpest = turn;
      start = j;
    }
  }
  // Vertex j of the rotated list as an unwrapped contour index.
  std::vector<size_t> idx(m + 1);
  for (size_t j = 0; j <= m; ++j) {
    size_t k = v[(start + j) % m];
    if (j > 0 && k <= idx[j - 1]) k += n * ((idx[j - 1] - k) / n + 1);
    idx[j] = k;
  }
  idx[m] = idx[0] + n;
  return idx;
}
}  // namespace

double Primitive::length() const {
  if (kind == PrimitiveKind::kLine) return std::hypot(end.x - start.x, end.y - start.y);
  return std::abs(sweep_deg) * kRadPerDeg * radius;
}

int edgeOffsetCount(double length) { return std::max(1, static_cast<int>(std::floor(length))); }

int16_t edgeOffsetMpx(double px) {
  return static_cast<int16_t>(
      std::lround(1000.0 * std::clamp(px, -kMaxEdgeOffsetPx, kMaxEdgeOffsetPx)));
}

double Primitive::edgeOffsetAt(double t) const {
  const auto& o = edge_offsets_mpx;
  if (o.empty()) return 0;
  const double at =
      std::clamp(t * static_cast<double>(o.size()) - 0.5, 0.0, static_cast<double>(o.size() - 1));
  const auto k = static_cast<size_t>(at);
  const size_t next = std::min(k + 1, o.size() - 1);
  const double w = at - static_cast<double>(k);
  return 0.001 * ((1 - w) * o[k] + w * o[next]);
}

int Primitive::weightPctAt(double t) const {
  const auto& w = edge_weights_pct;
  if (w.empty()) return 100;
  return w[std::min(w.size() - 1, static_cast<size_t>(std::max(0.0, t * w.size())))];
}

cv::Point2d Primitive::pointAt(double t) const {
  if (kind == PrimitiveKind::kLine) return start + (end - start) * t;
  const double a = angleOf(start - centre) * kRadPerDeg + t * sweep_deg * kRadPerDeg;
  return centre + cv::Point2d(std::cos(a), std::sin(a)) * radius;
}

cv::Point2d Primitive::startDirection() const {
  if (kind == PrimitiveKind::kLine) return unit(end - start);
  const cv::Point2d r = unit(start - centre);
  return sweep_deg >= 0 ? cv::Point2d(-r.y, r.x) : cv::Point2d(r.y, -r.x);
}

cv::Point2d Primitive::endDirection() const {
  if (kind == PrimitiveKind::kLine) return unit(end - start);
  const cv::Point2d r = unit(pointAt(1.0) - centre);
  return sweep_deg >= 0 ? cv::Point2d(-r.y, r.x) : cv::Point2d(r.y, -r.x);
}

const char* cornerClassName(CornerClass c) {
  switch (c) {
    case CornerClass::kLineLine:
      return "line-line";
    case CornerClass::kLineArc:
      return "line-arc";
    case CornerClass::kArcLine:
      return "arc-line";
    case CornerClass::kArcArc:
      return "arc-arc";
  }
  return "line-line";
}

std::vector<Primitive> fitPrimitives(const std::vector<cv::Point2d>& pts, double conformity) {
  const size_t n = pts.size();
  std::vector<Primitive> out;
  if (n < 2) return out;
  if (n < 4) {
    for (size_t i = 0; i < n; ++i) out.push_back(makeLine(pts[i], pts[(i + 1) % n]));
    return out;
  }
  const double extent = extentOf(pts);
  const std::vector<size_t> idx = polygonFromSharpest(pts, conformity);
  const size_t m = idx.size() - 1;

  const ContourSums sums(pts);
  const auto arcFits = [&](size_t first, size_t last, Circle* c) {
    if (!sums.fitCircle(first, last, c)) return false;
    if (c->radius > kMaxRadiusFactor * extent) return false;
    if (!withinOfCircle(pts, first, last, *c, conformity)) return false;
    // An arc flatter than the conformity is a line.
    const cv::Point2d chord = pts[last % n] - pts[first % n];
    const double half = 0.5 * std::hypot(chord.x, chord.y);
    const double sagitta =
        c->radius - std::sqrt(std::max(0.0, c->radius * c->radius - half * half));
    return sagitta > conformity || std::abs(sweepOf(pts, first, last, c->centre)) > 180;
  };

  // A loop that is one circle (a hole, a disc) has no corner at all.
  Circle whole;
  if (sums.fitCircle(0, n - 1, &whole) && withinOfCircle(pts, 0, n - 1, whole, conformity) &&
      whole.radius <= kMaxRadiusFactor * extent) {
    Primitive p;
    p.kind = PrimitiveKind::kArc;
    p.centre = whole.centre;
    p.radius = whole.radius;
    p.start = onCircle(whole, pts[0]);
    p.end = p.start;
    p.sweep_deg = sweepOf(pts, 0, n, whole.centre) >= 0 ? 360.0 : -360.0;
    out.push_back(p);
    return out;
  }

  for (size_t j = 0; j < m;) {
    size_t best = j;
    Circle best_circle;
    for (size_t k = j + 1; k < m; ++k) {
      Circle c;
      if (!arcFits(idx[j], idx[k + 1], &c)) break;
      best = k;
      best_circle = c;
    }
    if (best > j) {
      Primitive p;
      p.kind = PrimitiveKind::kArc;
      p.centre = best_circle.centre;
      p.radius = best_circle.radius;
      p.start = onCircle(best_circle, pts[idx[j] % n]);
      p.end = onCircle(best_circle, pts[idx[best + 1] % n]);
      p.sweep_deg = sweepOf(pts, idx[j], idx[best + 1], best_circle.centre);
      out.push_back(p);
    } else {
      out.push_back(makeLine(pts[idx[j] % n], pts[idx[j + 1] % n]));
    }
    j = best + 1;
  }
  return out;
}

std::vector<BoundaryLoop> fitLoops(const std::vector<std::vector<cv::Point2d>>& contours,
                                   double conformity) {
  std::vector<BoundaryLoop> loops;
  for (size_t i = 0; i < contours.size(); ++i) {
    BoundaryLoop loop;
    loop.hole = i > 0;
    loop.primitives = fitPrimitives(contours[i], conformity);
    if (!loop.primitives.empty()) loops.push_back(std::move(loop));
  }
  return loops;
}

std::vector<Corner> findCorners(const std::vector<BoundaryLoop>& loops, double conformity) {
  std::vector<Corner> corners;
  for (size_t l = 0; l < loops.size(); ++l) {
    const auto& prims = loops[l].primitives;
    const size_t n = prims.size();
    if (n < 2) continue;
    // The loop's winding: the sum of turns is +-360.
    double winding = 0;
    for (size_t i = 0; i < n; ++i) {
      const Primitive& a = prims[i];
      const Primitive& b = prims[(i + 1) % n];
      winding += signedDeg(angleOf(b.startDirection()) - angleOf(a.endDirection()));
      if (a.kind == PrimitiveKind::kArc) winding += a.sweep_deg;
    }
    for (size_t i = 0; i < n; ++i) {
      const Primitive& a = prims[i];
      const Primitive& b = prims[(i + 1) % n];
      Corner c;
      const bool arc_in = a.kind == PrimitiveKind::kArc;
      const bool arc_out = b.kind == PrimitiveKind::kArc;
      c.kind = arc_in ? (arc_out ? CornerClass::kArcArc : CornerClass::kArcLine)
                      : (arc_out ? CornerClass::kLineArc : CornerClass::kLineLine);
      c.loop = static_cast<int>(l);
      c.index = static_cast<int>((i + 1) % n);
      c.at = 0.5 * (a.end + b.start);
      c.direction_in_deg = angleOf(a.endDirection());
      c.direction_out_deg = angleOf(b.startDirection());
      const double turn = signedDeg(c.direction_out_deg - c.direction_in_deg);
      // Turn ranges widen for short edges, whose directions are less sure.
      const double slack =
          8.0 + std::atan2(2 * conformity, std::min(a.length(), b.length())) / kRadPerDeg;
      c.turn_deg = {turn - slack, turn + slack};
      c.convex = (turn >= 0) == (winding >= 0);
      const double tol = 2 * conformity;
      c.length_in = {0, a.length() + tol};
      c.length_out = {0, b.length() + tol};
      c.radius_in = arc_in ? Range{0.8 * a.radius - tol, 1.2 * a.radius + tol} : Range{};
      c.radius_out = arc_out ? Range{0.8 * b.radius - tol, 1.2 * b.radius + tol} : Range{};
      corners.push_back(c);
    }
  }
  return corners;
}

std::vector<BoundarySample> sampleBoundary(const std::vector<BoundaryLoop>& loops, double step) {
  std::vector<BoundarySample> samples;
  for (const auto& loop : loops) {
    for (const auto& p : loop.primitives) {
      const double length = p.length();
      const int count = std::max(1, static_cast<int>(std::ceil(length / step)));
      for (int i = 0; i < count; ++i) {
        const double t = (i + 0.5) / count;
        samples.push_back({p.pointAt(t), loop.weight * p.weightAt(t) * length / count});
      }
    }
  }
  return samples;
}

double primitiveDistance(const Primitive& prim, cv::Point2d p) {
  double d = std::min(std::hypot(p.x - prim.start.x, p.y - prim.start.y),
                      std::hypot(p.x - prim.end.x, p.y - prim.end.y));
  if (prim.kind == PrimitiveKind::kLine) {
    const cv::Point2d v = prim.end - prim.start;
    const double n2 = v.dot(v);
    if (n2 > 0) {
      const double t = (p - prim.start).dot(v) / n2;
      if (t > 0 && t < 1) d = std::min(d, pointLineDistance(p, prim.start, prim.end));
    }
  } else {
    // On the arc when the point's direction from the centre lies within
    // the sweep, walked the arc's way from its start.
    const cv::Point2d r = p - prim.centre;
    double along = angleOf(r) - angleOf(prim.start - prim.centre);
    if (prim.sweep_deg < 0) along = -along;
    along = along - 360.0 * std::floor(along / 360.0);
    if (along <= std::abs(prim.sweep_deg)) {
      d = std::min(d, std::abs(std::hypot(r.x, r.y) - prim.radius));
    }
  }
  return d;
}

namespace {
// The squared distance from `p` to a box that holds every point of `prim`
// (a line's ends; an arc's whole circle): no point of the primitive lies
// nearer, so one whose box lies at least as far as the nearest distance
// found so far cannot lower it.
double squaredBoxDistance(const Primitive& prim, cv::Point2d p) {
  double x0, x1, y0, y1;
  if (prim.kind == PrimitiveKind::kLine) {
    x0 = std::min(prim.start.x, prim.end.x);
    x1 = std::max(prim.start.x, prim.end.x);
    y0 = std::min(prim.start.y, prim.end.y);
    y1 = std::max(prim.start.y, prim.end.y);
  } else {
    x0 = prim.centre.x - prim.radius;
    x1 = prim.centre.x + prim.radius;
    y0 = prim.centre.y - prim.radius;
    y1 = prim.centre.y + prim.radius;
  }
  const double dx = p.x < x0 ? x0 - p.x : p.x > x1 ? p.x - x1 : 0.0;
  const double dy = p.y < y0 ? y0 - p.y : p.y > y1 ? p.y - y1 : 0.0;
  return dx * dx + dy * dy;
}
}  // namespace

double boundaryDistance(const std::vector<BoundaryLoop>& loops, cv::Point2d p) {
  PrimitiveIndex nearest;
  return boundaryDistance(loops, p, &nearest);
}

double boundaryDistance(const std::vector<BoundaryLoop>& loops, cv::Point2d p,
                        PrimitiveIndex* nearest) {
  // The exact distance of only those primitives whose box may hold a nearer
  // point: the same minimum, in a fraction of the arithmetic (training asks
  // it of every boundary sample, turned, for the symmetry and hand tests:
  // most of a model's training time). The last point's nearest primitive
  // first: the next point along a boundary is most often nearest to it too,
  // and every other box then lies farther.
  double best = std::numeric_limits<double>::infinity();
  const bool hinted =
      nearest->loop < loops.size() && nearest->primitive < loops[nearest->loop].primitives.size();
  if (hinted) best = primitiveDistance(loops[nearest->loop].primitives[nearest->primitive], p);
  for (size_t l = 0; l < loops.size(); ++l) {
    const auto& primitives = loops[l].primitives;
    for (size_t k = 0; k < primitives.size(); ++k) {
      if (squaredBoxDistance(primitives[k], p) >= best * best) continue;
      const double d = primitiveDistance(primitives[k], p);
      if (d < best) {
        best = d;
        *nearest = {l, k};
      }
    }
  }
  return best;
}

BoundaryDistanceMap::BoundaryDistanceMap(const std::vector<BoundaryLoop>& loops, double reach,
                                         double cell)
    : inv_cell_(1.0 / cell), reach_(static_cast<float>(reach)) {
  cv::Point2d lo(std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity());
  cv::Point2d hi = -lo;
  for (const auto& s : sampleBoundary(loops, cell)) {
    lo = {std::min(lo.x, s.point.x), std::min(lo.y, s.point.y)};
    hi = {std::max(hi.x, s.point.x), std::max(hi.y, s.point.y)};
  }
  if (!(lo.x <= hi.x)) return;
  const double margin = reach + 2 * cell;
  origin_ = lo - cv::Point2d(margin, margin);
  distance_.create(static_cast<int>(std::ceil((hi.y - lo.y + 2 * margin) * inv_cell_)) + 2,
                   static_cast<int>(std::ceil((hi.x - lo.x + 2 * margin) * inv_cell_)) + 2, CV_32F);
  distance_.setTo(reach_);
  last_ = cv::Point2d(distance_.cols - 1, distance_.rows - 1);
  // Each primitive writes its exact distance over its box grown by the
  // reach: work in proportion to the boundary's length, not the box's area.
  for (const auto& loop : loops) {
    for (const auto& prim : loop.primitives) {
      cv::Point2d a(std::min(prim.start.x, prim.end.x), std::min(prim.start.y, prim.end.y));
      cv::Point2d b(std::max(prim.start.x, prim.end.x), std::max(prim.start.y, prim.end.y));
      if (prim.kind == PrimitiveKind::kArc) {
        // The arc's extreme points may lie beyond its ends: its samples.
        for (int i = 1; i < 16; ++i) {
          const cv::Point2d q = prim.pointAt(i / 16.0);
          a = {std::min(a.x, q.x), std::min(a.y, q.y)};
          b = {std::max(b.x, q.x), std::max(b.y, q.y)};
        }
      }
      const int x0 =
          std::max(0, static_cast<int>(std::floor((a.x - reach - origin_.x) * inv_cell_)));
      const int y0 =
          std::max(0, static_cast<int>(std::floor((a.y - reach - origin_.y) * inv_cell_)));
      const int x1 = std::min(distance_.cols - 1,
                              static_cast<int>(std::ceil((b.x + reach - origin_.x) * inv_cell_)));
      const int y1 = std::min(distance_.rows - 1,
                              static_cast<int>(std::ceil((b.y + reach - origin_.y) * inv_cell_)));
      for (int y = y0; y <= y1; ++y) {
        float* row = distance_.ptr<float>(y);
        for (int x = x0; x <= x1; ++x) {
          const cv::Point2d p = origin_ + cv::Point2d(x * cell, y * cell);
          row[x] = std::min(row[x], static_cast<float>(primitiveDistance(prim, p)));
        }
      }
    }
  }
}

}  // namespace picksight::vision
