// Parts inside merged blobs: corners and arcs of the boundary model matched
// to those of the blob propose poses, the blob's edge-distance map verifies
// them, the grey-level edges refine them, and the best are accepted first.
#include "picksight/vision/touching_parts.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <optional>

#include "picksight/common/angles.hpp"

namespace picksight::vision {
namespace {
// A corner turning less than this has no reliable direction (a line running
// tangentially into an arc, a wobble of the fit).
constexpr double kMinCornerTurnDeg = 30;
// How far the opening angles of a model and an image corner may differ:
// directions of short fitted edges are a few degrees off.
constexpr double kCornerAngleSlackDeg = 15;
constexpr double kMinEdgePx = 4;
constexpr double kMaxChamferPx = 12;
constexpr double kMinArcSweepDeg = 50;
constexpr double kMinArcRadiusPx = 4;
// Hypotheses are screened on this many boundary samples before a full check,
// after a first look at a quarter of them.
constexpr size_t kSparseSamples = 64;
constexpr size_t kGlanceSamples = 16;
// The first look's score may fall this far below the screening threshold
// (16 samples judge a pose more roughly).
constexpr double kGlanceSlack = 0.1;
// Curved outlines break into many primitives: the hypotheses come from the
// most telling few, so that the cost does not grow with their number. A
// part is found from any one of its corners or arcs that shows.
constexpr size_t kMaxModelCorners = 32;
constexpr size_t kMaxModelArcs = 4;
// The rotation scan about an arc first steps this far at the model's rim.
constexpr double kCoarseScanStepPx = 4.0;
// Screening score a hypothesis needs, below the verify fraction: a pose from
// one corner is a few degrees off, which costs verification at the rim.
constexpr double kCoarseSlack = 0.25;
// Rotation scan about an arc's centre: the largest step at the model's rim.
constexpr double kScanStepPx = 1.5;
constexpr int kMaxRefinedPerModel = 8;
// Poses refined per blob, for each part the blob can hold: the best
// screened hypotheses of all models, so that a blob costs about the same
// whatever the number of trained types.
constexpr int kRefinedPerPart = 12;
constexpr int kMaxRefinedPerBlob = 48;
// Edge-fit iterations before the last two read every third edge sample:
// the pose is still settling there.
constexpr int kSparseFitStride = 3;
// A sparse iteration that moves the boundary by less than this (pixels, at
// the rim) has settled: the remaining sparse ones are skipped.
constexpr double kSettledPx = 0.01;
// A mirror-image candidate that verifies within this of the direct one
// makes the handedness a question: where the two hands differ decides it
// (showsMirrorImage), and a part shown mirrored is not reported.
constexpr double kMirrorMargin = 0.03;
// Parts that touch share at most their contact pixels, parts that overlap
// (one lying on another, a quarter of its outline hidden) a fifth of their
// area; a part lies in its blob.
constexpr double kMaxOverlap = 0.2;
constexpr double kMaxOutside = 0.06;
// Edge samples this close to a primitive's end see the neighbouring edge.
constexpr double kCornerClearancePx = 2.0;

double angleOf(cv::Point2d v) { return std::atan2(v.y, v.x) / kRadPerDeg; }

using picksight::angleDiffDeg;
using picksight::kRadPerDeg;
using picksight::normalizeDeg;
using picksight::signedDeg;
using picksight::wrapDeg;

cv::Point2d rotate(cv::Point2d p, double c, double s) {
  return {c * p.x - s * p.y, s * p.x + c * p.y};
}

// Twice the signed area of a loop: > 0 when its interior lies on the side of
// the left normal (-t.y, t.x) of the walking direction t.
double loopOrientation(const BoundaryLoop& loop) {
  std::vector<cv::Point2d> pts;
  for (const auto& p : loop.primitives) {
    const int n = p.kind == PrimitiveKind::kArc ? 16 : 1;
    for (int i = 0; i < n; ++i) pts.push_back(p.pointAt(static_cast<double>(i) / n));
  }
  double a = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    const cv::Point2d& p = pts[i];
    const cv::Point2d& q = pts[(i + 1) % pts.size()];
    a += p.x * q.y - q.x * p.y;
  }
  return a;
}

// A corner as an unordered pair of edges leaving a point, so that it reads
// the same on a mirrored model: the bisector of the two edges, the opening
// angle between them, and whether the body fills the opening.
struct CornerAnchor {
  cv::Point2d at;
  double bisector_deg = 0;
  double opening_deg = 0;
  bool convex = true;
};

struct ArcAnchor {
  cv::Point2d centre;
  double radius = 0;
  double length = 0;
  double mid_deg = 0;    // direction of the arc's middle from its centre
  double sweep_deg = 0;  // signed, in the loop's walking direction
};

void anchorsOf(const std::vector<BoundaryLoop>& loops, std::vector<CornerAnchor>* corners,
               std::vector<ArcAnchor>* arcs) {
  for (const auto& loop : loops) {
    const auto& prims = loop.primitives;
    const size_t n = prims.size();
    const bool left_interior = loopOrientation(loop) > 0;
    // Corners between long edges, each also across the next long edge when
    // that one is short: a corner the fit cut off with a chamfer (a blurred
    // sharp tip, pixel steps, a contact point) is still one corner, at the
    // meeting of its two edges' tangents.
    std::vector<size_t> long_edges;
    for (size_t i = 0; i < n; ++i) {
      if (prims[i].length() >= kMinEdgePx) long_edges.push_back(i);
    }
    const size_t count = n >= 2 ? long_edges.size() : 0;
    for (size_t k = 0; count >= 2 && k < count; ++k) {
      for (size_t skip = 1; skip <= std::min<size_t>(2, count - 1); ++skip) {
        const Primitive& a = prims[long_edges[k]];
        const Primitive& b = prims[long_edges[(k + skip) % count]];
        if (cv::norm(b.start - a.end) > kMaxChamferPx) continue;
        const cv::Point2d in = a.endDirection();
        const cv::Point2d out = b.startDirection();
        const double turn = signedDeg(angleOf(out) - angleOf(in));
        if (std::abs(turn) < kMinCornerTurnDeg) continue;
        const cv::Point2d u = out - in;
        if (std::hypot(u.x, u.y) < 1e-6) continue;
        // a.end + p in = b.start - q out, solved for p.
        const cv::Point2d gap = b.start - a.end;
        const double det = in.x * out.y - in.y * out.x;
        const double along = (gap.x * out.y - gap.y * out.x) / det;
        const bool loop_convex = (turn > 0) == left_interior;
        corners->push_back({a.end + in * along, angleOf(u), 180.0 - std::abs(turn),
                            loop.hole ? !loop_convex : loop_convex});
      }
    }
    for (const auto& p : prims) {
      if (p.kind == PrimitiveKind::kArc && std::abs(p.sweep_deg) >= kMinArcSweepDeg &&
          p.radius >= kMinArcRadiusPx) {
        arcs->push_back(
            {p.centre, p.radius, p.length(), angleOf(p.pointAt(0.5) - p.centre), p.sweep_deg});
      }
    }
  }
}

// A boundary point of the model with its normal pointing away from the body.
struct EdgeSample {
  cv::Point2d point;
  cv::Point2d normal;
  double weight = 0;
};

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

std::vector<EdgeSample> edgeSamples(const PartModel& model, double step) {
  std::vector<EdgeSample> out;
  for (const auto& loop : model.loops) {
    const bool left_interior = loopOrientation(loop) > 0;
    for (const auto& p : loop.primitives) {
      alongPrimitive(p, loop.primitives.size() == 1, loop.weight, step, [&](double t, double w) {
        out.push_back({p.pointAt(t), awayNormal(p, t, left_interior, loop.hole), w});
      });
    }
  }
  return out;
}

// Bilinear reading of a region's coverage (0 outside its box).
class Coverage {
 public:
  explicit Coverage(const Region& r) : c_(r.coverage), origin_(r.coverage_origin) {}
  float at(cv::Point2d p) const {
    const double x = p.x - origin_.x;
    const double y = p.y - origin_.y;
    const int x0 = static_cast<int>(std::floor(x));
    const int y0 = static_cast<int>(std::floor(y));
    if (x0 < 0 || y0 < 0 || x0 + 1 >= c_.cols || y0 + 1 >= c_.rows) return 0.f;
    const float fx = static_cast<float>(x - x0);
    const float fy = static_cast<float>(y - y0);
    const float* r0 = c_.ptr<float>(y0) + x0;
    const float* r1 = c_.ptr<float>(y0 + 1) + x0;
    return (1 - fy) * ((1 - fx) * r0[0] + fx * r0[1]) + fy * ((1 - fx) * r1[0] + fx * r1[1]);
  }

 private:
  const cv::Mat& c_;
  cv::Point origin_;
};

// Where, along p + s n (n pointing away from the body), the coverage falls
// through 0.5 from a clean inside to a clean outside, nearest to `expected`;
// none where the part touches another (no outside) or the edge is a mess.
std::optional<double> edgeCrossing(const Coverage& cov, cv::Point2d p, cv::Point2d n, double window,
                                   double expected, double step) {
  std::optional<double> best;
  double previous = cov.at(p - n * window);
  for (double s = -window + step; s <= window + 1e-9; s += step) {
    const double v = cov.at(p + n * s);
    if (previous >= 0.5 && v < 0.5) {
      const double at = s - step + step * (previous - 0.5) / (previous - v);
      if (!best || std::abs(at - expected) < std::abs(*best - expected)) {
        if (cov.at(p + n * (at - 1.5)) >= 0.7 && cov.at(p + n * (at + 1.5)) <= 0.3) best = at;
      }
    }
    previous = v;
  }
  return best;
}

std::vector<BoundarySample> sparseSamples(const std::vector<BoundarySample>& all, size_t count) {
  const size_t stride = std::max<size_t>(1, all.size() / count);
  std::vector<BoundarySample> out;
  for (size_t i = stride / 2; i < all.size(); i += stride) out.push_back(all[i]);
  return out;
}

// A part lying partly under another shows less of its boundary: what is
// not on an edge may lie on the other part's body, never on the background.
// It then needs this much of its boundary on edges, and the verify fraction
// of what is not hidden.
constexpr double kMinVisible = 0.7;

// Whether the boundary a pose leaves off the edges lies on the blob's body
// (hidden by a part lying on it) enough to explain the score.
bool hiddenUnderOthers(const PartModel& m, const ImagePose& pose, const EdgeDistance& edges,
                       const Coverage& coverage, double score) {
  if (score < kMinVisible) return false;
  const double c = std::cos(pose.angle_deg * kRadPerDeg);
  const double s = std::sin(pose.angle_deg * kRadPerDeg);
  const double flip = pose.mirrored ? -1.0 : 1.0;
  double on = 0;
  double missing = 0;
  for (const auto& sample : m.samples) {
    const cv::Point2d p = pose.centre + rotate({sample.point.x, flip * sample.point.y}, c, s);
    if (edges.at(p) <= m.edge_tolerance) {
      on += sample.weight;
    } else if (coverage.at(p) < 0.5) {
      missing += sample.weight;
    }
  }
  return on + missing > 0 && on / (on + missing) * 100 >= m.verify_percent;
}

struct Candidate {
  const PartModel* model = nullptr;
  ImagePose pose;
  double score = 0;
  double rms = 0;
};

bool samePose(const PartModel& m, const ImagePose& a, const ImagePose& b, double px, double deg) {
  if (a.mirrored != b.mirrored) return false;
  if (std::hypot(a.centre.x - b.centre.x, a.centre.y - b.centre.y) > px) return false;
  // A period of 0 (any turn looks the same): the angles always agree.
  return angleDiffDeg(a.angle_deg, b.angle_deg, m.symmetryDeg()) <= deg;
}

// The model's loops placed at a pose, as polygons in canvas coordinates:
// filled together, the holes stay empty.
std::vector<std::vector<cv::Point>> placedOutline(const PartModel& m, const ImagePose& pose,
                                                  cv::Point origin) {
  std::vector<std::vector<cv::Point>> polys;
  const double c = std::cos(pose.angle_deg * kRadPerDeg);
  const double s = std::sin(pose.angle_deg * kRadPerDeg);
  const double flip = pose.mirrored ? -1.0 : 1.0;
  for (const auto& loop : m.loops) {
    std::vector<cv::Point> poly;
    for (const auto& p : loop.primitives) {
      const int n = std::max(1, static_cast<int>(p.length() / 2.0));
      for (int i = 0; i < n; ++i) {
        const cv::Point2d q = p.pointAt(static_cast<double>(i) / n);
        const cv::Point2d r = pose.centre + rotate({q.x, flip * q.y}, c, s);
        poly.emplace_back(static_cast<int>(std::lround(r.x)) - origin.x,
                          static_cast<int>(std::lround(r.y)) - origin.y);
      }
    }
    polys.push_back(std::move(poly));
  }
  return polys;
}

// The most telling anchors of a model: its sharpest corners and its
// longest arcs.
void keepTelling(std::vector<CornerAnchor>* corners, std::vector<ArcAnchor>* arcs) {
  if (corners->size() > kMaxModelCorners) {
    std::stable_sort(corners->begin(), corners->end(),
                     [](const CornerAnchor& a, const CornerAnchor& b) {
                       return std::abs(180 - a.opening_deg) > std::abs(180 - b.opening_deg);
                     });
    corners->resize(kMaxModelCorners);
  }
  if (arcs->size() > kMaxModelArcs) {
    std::stable_sort(arcs->begin(), arcs->end(),
                     [](const ArcAnchor& a, const ArcAnchor& b) { return a.length > b.length; });
    arcs->resize(kMaxModelArcs);
  }
}

}  // namespace

struct BlobSearchModel {
  std::vector<CornerAnchor> corners;   // the most telling (keepTelling)
  std::vector<ArcAnchor> arcs;         // likewise
  std::vector<BoundarySample> sparse;  // hypotheses are screened on these
  std::vector<BoundarySample> glance;  // after a first look at these
  std::vector<EdgeSample> edges;       // poses are refined on these, 1 px apart
  double glance_weight = 0;            // the glance samples' total
};

std::shared_ptr<const BlobSearchModel> makeBlobSearchModel(const PartModel& model) {
  auto b = std::make_shared<BlobSearchModel>();
  anchorsOf(model.loops, &b->corners, &b->arcs);
  keepTelling(&b->corners, &b->arcs);
  b->sparse = sparseSamples(model.samples, kSparseSamples);
  b->glance = sparseSamples(model.samples, kGlanceSamples);
  for (const auto& g : b->glance) b->glance_weight += g.weight;
  b->edges = edgeSamples(model, 1.0);
  return b;
}

namespace {
// The model's side of the search: derived by prepareModel, or here for a
// model put together without it.
std::shared_ptr<const BlobSearchModel> searchOf(const PartModel& m) {
  return m.blob_search ? m.blob_search : makeBlobSearchModel(m);
}

// A blob's arc is a piece of the model's arc it matches, or the model's arc
// a piece of it (the contact cuts arcs, the fit breaks a curved outline
// where it likes): the turn that lines up their middles is off by at most
// half the difference of their sweeps, and this for where the breaks fell.
constexpr double kArcSlideDeg = 30;
constexpr double kCircleDeg = 359;
// A corner's first look counts boundary samples within this many edge
// tolerances; the search of its turn then starts at this step, each step
// halved down to the finest.
constexpr double kLooseScreenFactor = 2.0;
constexpr double kCornerTurnStepDeg = 2.0;
constexpr double kCornerTurnFinestDeg = 0.5;

// Whether at least `needed` (a fraction) of the samples' weight lies within
// `tolerance` of an edge at the pose (centre, turn with cosine c and sine s,
// mirrored when flip is -1), as verifyScore would say; stops as soon as the
// rest cannot decide otherwise, which most wrong hypotheses show within a
// few samples.
bool verifiesAtLeast(const std::vector<BoundarySample>& samples, double total, cv::Point2d centre,
                     double c, double s, double flip, const EdgeDistance& edges, double tolerance,
                     double needed) {
  const double goal = needed * total;
  double on = 0;
  double left = total;
  for (const auto& sample : samples) {
    const double x = sample.point.x;
    const double y = flip * sample.point.y;
    if (edges.at({centre.x + c * x - s * y, centre.y + s * x + c * y}) <= tolerance) {
      on += sample.weight;
      if (on >= goal) return true;
    }
    left -= sample.weight;
    if (on + left < goal) return false;
  }
  return on >= goal;
}

// Screens the poses proposed for one model (direct or mirrored) in a blob.
void propose(const PartModel& model, const BlobSearchModel& search, bool mirrored,
             const std::vector<CornerAnchor>& image_corners,
             const std::vector<ArcAnchor>& image_arcs, const EdgeDistance& edges,
             std::vector<Candidate>* out) {
  const auto& sparse = search.sparse;
  const auto& glance = search.glance;
  const double threshold = model.verify_percent / 100.0 - kCoarseSlack;
  const double f = mirrored ? -1.0 : 1.0;
  // The pose putting model point `model_point` on `image_point` turned by
  // `angle`, scored on `samples`.
  const auto screen = [&](cv::Point2d model_point, cv::Point2d image_point, double angle,
                          const std::vector<BoundarySample>& samples) {
    const double c = std::cos(angle * kRadPerDeg);
    const double s = std::sin(angle * kRadPerDeg);
    const cv::Point2d centre = image_point - rotate({model_point.x, f * model_point.y}, c, s);
    const double score = verifyScore(samples, centre, angle, edges, model.edge_tolerance, mirrored);
    return Candidate{&model, ImagePose{centre, normalizeDeg(angle), mirrored}, score, 0};
  };
  // A corner's direction is a few degrees off (its edges are short): the
  // first look forgives that with a wider tolerance, and the turn about the
  // corner is then searched coarse to fine on the screening samples.
  const double loose = kLooseScreenFactor * model.edge_tolerance;
  for (const auto& mc : search.corners) {
    for (const auto& ic : image_corners) {
      if (mc.convex != ic.convex) continue;
      if (std::abs(mc.opening_deg - ic.opening_deg) > kCornerAngleSlackDeg) continue;
      const double angle = ic.bisector_deg - f * mc.bisector_deg;
      const double cosine = std::cos(angle * kRadPerDeg);
      const double sine = std::sin(angle * kRadPerDeg);
      const cv::Point2d centre = ic.at - rotate({mc.at.x, f * mc.at.y}, cosine, sine);
      if (!verifiesAtLeast(glance, search.glance_weight, centre, cosine, sine, f, edges, loose,
                           threshold - kGlanceSlack)) {
        continue;
      }
      Candidate c = screen(mc.at, ic.at, angle, sparse);
      for (double step = kCornerTurnStepDeg; step >= kCornerTurnFinestDeg; step /= 2) {
        const double at = c.pose.angle_deg;
        for (int k = -2; k <= 2; ++k) {
          if (k == 0 || (step < kCornerTurnStepDeg && std::abs(k) > 1)) continue;
          const Candidate n = screen(mc.at, ic.at, at + k * step, sparse);
          if (n.score > c.score) c = n;
        }
      }
      if (c.score >= threshold) out->push_back(c);
    }
  }
  // An arc fixes where its centre goes; the turn about it lines up the two
  // arcs (kArcSlideDeg), scanned coarsely at a glance, and around each
  // promising step finely. The placed hand walks the model's arc the way
  // the blob's arc goes: a mirror reverses it.
  const double fine = kScanStepPx / std::max(model.radius, 1.0) / kRadPerDeg;
  const double coarse = kCoarseScanStepPx / std::max(model.radius, 1.0) / kRadPerDeg;
  std::vector<double> scan;
  for (const auto& ma : search.arcs) {
    for (const auto& ia : image_arcs) {
      if (std::abs(ia.radius - ma.radius) > std::max(2.0, 0.12 * ma.radius)) continue;
      if ((ia.sweep_deg > 0) != (f * ma.sweep_deg > 0)) continue;
      const double middle = ia.mid_deg - f * ma.mid_deg;
      // A whole circle's ends are wherever its loop started: any turn.
      const bool circle = std::max(std::abs(ma.sweep_deg), std::abs(ia.sweep_deg)) >= kCircleDeg;
      const double half =
          circle ? 180.0
                 : std::min(180.0, 0.5 * std::abs(std::abs(ma.sweep_deg) - std::abs(ia.sweep_deg)) +
                                       kArcSlideDeg);
      const int steps = static_cast<int>(std::ceil(2 * half / coarse)) + 1;
      const double step = 2 * half / (steps - 1);
      scan.resize(static_cast<size_t>(steps));
      for (int k = 0; k < steps; ++k)
        scan[k] = screen(ma.centre, ia.centre, middle - half + k * step, glance).score;
      for (int k = 0; k < steps; ++k) {
        const double s = scan[k];
        if (s < threshold - kGlanceSlack || (k > 0 && s < scan[k - 1]) ||
            (k + 1 < steps && s <= scan[k + 1])) {
          continue;
        }
        Candidate best;
        best.score = -1;
        const double at = middle - half + k * step;
        for (double a = at - step; a <= at + step; a += fine) {
          const Candidate c = screen(ma.centre, ia.centre, a, sparse);
          if (c.score > best.score) best = c;
        }
        if (best.score >= threshold) out->push_back(best);
      }
    }
  }
}
}  // namespace

EdgeFit refinePoseOnEdges(const PartModel& model, const Region& region, const ImagePose& start,
                          double search_px, int iterations) {
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
  // The last pass only measures: residuals and inliers at the final pose.
  for (int it = 0; it <= iterations; ++it) {
    const bool measure_only = it == iterations;
    const double c = std::cos(fit.pose.angle_deg * kRadPerDeg);
    const double s = std::sin(fit.pose.angle_deg * kRadPerDeg);
    const double step = window > 2.0 ? 0.5 : 0.25;
    cv::Matx44d a = cv::Matx44d::zeros();
    cv::Vec4d b(0, 0, 0, 0);
    double found = 0;
    double sum2 = 0;
    int used = 0;
    const size_t stride = it < iterations - 2 ? kSparseFitStride : 1;
    for (size_t i = 0; i < samples.size(); i += stride) {
      const EdgeSample& e = samples[i];
      const cv::Point2d r = rotate({e.point.x, flip * e.point.y}, c, s);
      const cv::Point2d n = rotate({e.normal.x, flip * e.normal.y}, c, s);
      const auto crossing = edgeCrossing(cov, fit.pose.centre + r, n, window, offset, step);
      if (!crossing || std::abs(*crossing - offset) > gate) continue;
      const double residual = *crossing - offset;
      found += e.weight;
      sum2 += residual * residual;
      ++used;
      if (measure_only) continue;
      const cv::Vec4d j(n.x, n.y, n.x * -r.y + n.y * r.x, 1.0);
      a += e.weight * (j * j.t());
      b += e.weight * *crossing * j;
    }
    if (used < 8) return fit;
    const double rms = std::sqrt(sum2 / used);
    fit.rms_px = rms;
    fit.inlier_fraction = found * static_cast<double>(stride) / total;
    if (measure_only) break;
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
      if (p.kind == PrimitiveKind::kLine) {
        if (edge.size() < 4) continue;
        cv::Vec4f line;
        std::vector<cv::Point2f> pts(edge.begin(), edge.end());
        cv::fitLine(pts, line, cv::DIST_L2, 0, 0.01, 0.01);
        const cv::Point2d d(line[0], line[1]);
        const cv::Point2d c = cv::Point2d(line[2], line[3]) - origin;
        p.start = c + d * (p.start - c).dot(d);
        p.end = c + d * (p.end - c).dot(d);
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
        p.centre = centre;
        p.radius = radius;
        p.start = onCircle(p.start);
        p.end = onCircle(p.end);
      }
    }
  }
}

std::vector<Match> locateInBlob(const std::vector<Region>& regions, size_t index,
                                const std::vector<const PartModel*>& models) {
  std::vector<Match> found;
  const Region& region = regions[index];
  double tolerance = 0;
  double conformity = 1e9;
  std::vector<const PartModel*> fitting;
  for (const PartModel* m : models) {
    // A part in the blob is no larger than the blob.
    if (m->loops.empty() || m->body.area * (1 - m->body.area_tolerance) > region.area) continue;
    fitting.push_back(m);
    tolerance = std::max(tolerance, m->edge_tolerance);
    conformity = std::min(conformity, m->conformity);
  }
  if (fitting.empty()) return found;

  std::vector<std::vector<cv::Point>> contours{region.outer};
  contours.insert(contours.end(), region.hole_boundaries.begin(), region.hole_boundaries.end());
  const double screen_reach = kLooseScreenFactor * tolerance;
  const int margin = static_cast<int>(std::ceil(screen_reach)) + 2;
  // Only verifyScore reads it, at no more than the loose screening tolerance.
  const EdgeDistance edges(
      contours,
      cv::Rect(region.bbox.x - margin, region.bbox.y - margin, region.bbox.width + 2 * margin,
               region.bbox.height + 2 * margin),
      screen_reach);
  std::vector<std::vector<cv::Point2d>> loops2d;
  for (const auto& c : contours) loops2d.emplace_back(c.begin(), c.end());
  std::vector<CornerAnchor> image_corners;
  std::vector<ArcAnchor> image_arcs;
  anchorsOf(fitLoops(loops2d, conformity), &image_corners, &image_arcs);

  // The best screened poses of each model and hand, then the best of all.
  std::vector<Candidate> screened;
  double smallest = region.area;
  for (const PartModel* m : fitting) {
    smallest = std::min(smallest, m->body.area);
    for (const bool mirrored : {false, true}) {
      if (mirrored && m->body.mirror_symmetric) continue;
      std::vector<Candidate> proposed;
      propose(*m, *searchOf(*m), mirrored, image_corners, image_arcs, edges, &proposed);
      std::stable_sort(proposed.begin(), proposed.end(),
                       [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
      std::vector<ImagePose> kept;
      for (const auto& p : proposed) {
        if (static_cast<int>(kept.size()) >= kMaxRefinedPerModel) break;
        const auto near = [&](const ImagePose& q) { return samePose(*m, p.pose, q, 2.0, 3.0); };
        if (std::any_of(kept.begin(), kept.end(), near)) continue;
        kept.push_back(p.pose);
        screened.push_back(p);
      }
    }
  }
  std::stable_sort(screened.begin(), screened.end(),
                   [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
  const int parts = std::max(1, static_cast<int>(region.area / std::max(smallest, 1.0)));
  const auto budget =
      static_cast<size_t>(std::min(kMaxRefinedPerBlob, kRefinedPerPart * (parts + 1)));
  if (screened.size() > budget) screened.resize(budget);

  std::vector<Candidate> direct;
  std::vector<Candidate> mirror;
  for (const auto& p : screened) {
    const PartModel* m = p.model;
    const EdgeFit fit = refinePoseOnEdges(*m, region, p.pose);
    if (!fit.ok) continue;
    auto& to = p.pose.mirrored ? mirror : direct;
    const auto same = [&](const Candidate& q) {
      return q.model == m && samePose(*m, fit.pose, q.pose, 1.0, 1.0);
    };
    if (std::any_of(to.begin(), to.end(), same)) continue;
    const double score = verifyScore(m->samples, fit.pose.centre, fit.pose.angle_deg, edges,
                                     m->edge_tolerance, p.pose.mirrored);
    to.push_back({m, fit.pose, score, fit.rms_px});
  }

  // Best first; among equal scores the closer fit to the grey-level edges.
  std::stable_sort(direct.begin(), direct.end(), [](const Candidate& a, const Candidate& b) {
    return a.score > b.score + 1e-9 || (std::abs(a.score - b.score) <= 1e-9 && a.rms < b.rms);
  });
  // A canvas around the blob wide enough for any part placed on it, so that
  // what a placed part has outside the blob is counted.
  double reach = 0;
  for (const PartModel* m : fitting) reach = std::max(reach, m->radius);
  const int pad = static_cast<int>(std::ceil(reach)) + 2;
  const cv::Point origin = region.coverage_origin - cv::Point(pad, pad);
  cv::Mat inside(region.coverage.rows + 2 * pad, region.coverage.cols + 2 * pad, CV_8UC1,
                 cv::Scalar(0));
  cv::compare(region.coverage, 0.5, inside(cv::Rect(cv::Point(pad, pad), region.coverage.size())),
              cv::CMP_GE);
  cv::Mat claimed(inside.size(), CV_8UC1, cv::Scalar(0));
  cv::Mat shape(inside.size(), CV_8UC1);
  const Coverage coverage(region);
  for (const auto& c : direct) {
    const PartModel& m = *c.model;
    if (c.score * 100 < m.verify_percent &&
        !hiddenUnderOthers(m, c.pose, edges, coverage, c.score)) {
      continue;
    }
    const bool mirror_as_good = std::any_of(mirror.begin(), mirror.end(), [&](const Candidate& q) {
      return q.model == c.model &&
             std::hypot(q.pose.centre.x - c.pose.centre.x, q.pose.centre.y - c.pose.centre.y) <
                 0.5 * m.radius &&
             q.score >= c.score - kMirrorMargin && showsMirrorImage(m, c.pose, q.pose, edges);
    });
    if (mirror_as_good) continue;
    // Only the placed part's box of the canvas is read and written.
    const auto outline = placedOutline(m, c.pose, origin);
    cv::Rect box;
    for (const auto& poly : outline) box |= cv::boundingRect(poly);
    box = (box + cv::Size(1, 1)) & cv::Rect(cv::Point(0, 0), shape.size());
    if (box.empty()) continue;
    cv::Mat drawn_here = shape(box);
    drawn_here.setTo(0);
    cv::fillPoly(drawn_here, outline, cv::Scalar(255), cv::LINE_8, 0, -box.tl());
    const int drawn = cv::countNonZero(drawn_here);
    if (drawn <= 0) continue;
    cv::Mat scratch;
    cv::bitwise_and(drawn_here, ~inside(box), scratch);
    const double outside = cv::countNonZero(scratch);
    cv::bitwise_and(drawn_here, claimed(box), scratch);
    const double overlap = cv::countNonZero(scratch);
    if (overlap > kMaxOverlap * drawn || outside > kMaxOutside * drawn) continue;
    cv::Mat claimed_here = claimed(box);
    cv::bitwise_or(claimed_here, drawn_here, claimed_here);
    Match match;
    match.model = c.model;
    match.region = index;
    match.score = c.score;
    match.centroid = c.pose.centre;
    match.symmetry_deg = m.symmetryDeg();
    match.angle_deg = wrapDeg(c.pose.angle_deg, match.symmetry_deg);
    match.touching = true;
    found.push_back(match);
  }
  return found;
}

}  // namespace picksight::vision
