// Pose hypotheses for parts in merged blobs: the corners and arcs of a
// model's boundary matched to those of the blob, each proposed pose screened
// on a few boundary samples against the blob's edge-distance map.
#include "picksight/vision/blob_search/touching_parts.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <optional>

#include "picksight/common/angles.hpp"
#include "touching_parts_internal.hpp"

namespace picksight::vision {
namespace touching {
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
// after a first look at a few of them (fewer let more wrong poses through
// to the screening; 12 found the most parts in the silhouette bench).
constexpr size_t kSparseSamples = 64;
// Two edges whose directions' cross product is below this (sine of the
// angle between them) are taken as parallel: their tangents' meeting point
// would be far away or at infinity.
constexpr double kMinCornerSine = 1e-6;
constexpr size_t kGlanceSamples = 12;
// The first look's score may fall this far below the screening threshold
// (the few samples judge a pose more roughly).
constexpr double kGlanceSlack = 0.1;
// In a blob's quick search, a corner's first look that falls short by no
// more than half a sample is taken again turned this far either way, and
// the search goes on from a turn that passes the screening threshold (the
// turn search covers as much again around it). A bell touching another
// part was found only from one corner whose bisector was 4 degrees off:
// its first look had 5 of 12 samples where 5.4 were needed, 12 of 12
// turned by 4 degrees, and numerical noise of 1e-9 in the model decided
// whether it was found. Costs 2.6 % more instructions in recognize() on
// touching scenes (taken in the full search as well: 11 %, for the poses it
// adds to refine).
constexpr double kGlanceNearMiss = 0.5 / kGlanceSamples;
constexpr double kGlanceTurnDeg = 4.0;
// Curved outlines break into many primitives: the hypotheses come from the
// most telling few, so that the cost does not grow with their number. A
// part is found from any one of its corners or arcs that shows.
constexpr size_t kMaxModelCorners = 32;
constexpr size_t kMaxModelArcs = 4;
// A blob's quick search starts from this many of a model's sharpest corners,
// and from its longest arc only when it has fewer corners (a scan about an
// arc costs as many first looks as a few dozen corners): enough to find
// most parts that show whole.
constexpr size_t kQuickCorners = 8;
constexpr size_t kQuickArcs = 1;
// The rotation scan about an arc first steps this far at the model's rim:
// a first look half a step off still screens a part there, and the fine
// scan covers a step either side (4 px found the same parts on the
// benchmark's four type sets, at 2.4 % more instructions in recognize() on
// touching scenes).
constexpr double kCoarseScanStepPx = 6.0;
// Screening score a hypothesis needs, below the verify fraction: a pose from
// one corner is a few degrees off, which costs verification at the rim.
constexpr double kCoarseSlack = 0.25;
// Rotation scan about an arc's centre: the largest step at the model's rim.
constexpr double kScanStepPx = 1.5;
// proposeAbout's reference points: a grid kAboutStepPx apart, this far
// either way of the middle it is given.
constexpr double kAboutReachPx = 12.0;
// Its first look: reference points this far apart (read kAboutWidePx more
// loosely).
constexpr double kAboutCoarsePx = 8.0;

// Points `step` apart within `reach` of (0, 0) either way, nearest first.
std::vector<cv::Point2d> aboutGrid(double step, double reach = kAboutReachPx) {
  std::vector<cv::Point2d> g;
  const int n = static_cast<int>(std::floor(reach / step + 1e-9));
  for (int j = -n; j <= n; ++j) {
    for (int i = -n; i <= n; ++i) g.emplace_back(i * step, j * step);
  }
  std::stable_sort(g.begin(), g.end(), [](cv::Point2d a, cv::Point2d b) {
    return a.x * a.x + a.y * a.y < b.x * b.x + b.y * b.y;
  });
  return g;
}

using picksight::normalizeDeg;
using picksight::signedDeg;

std::vector<BoundarySample> sparseSamples(const std::vector<BoundarySample>& all, size_t count) {
  const size_t stride = std::max<size_t>(1, all.size() / count);
  std::vector<BoundarySample> out;
  for (size_t i = stride / 2; i < all.size(); i += stride) out.push_back(all[i]);
  return out;
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

// A blob's arc is a piece of the model's arc it matches, or the model's arc
// a piece of it (the contact cuts arcs, the fit breaks a curved outline
// where it likes): the turn that lines up their middles is off by at most
// half the difference of their sweeps, and this for where the breaks fell.
constexpr double kArcSlideDeg = 30;
constexpr double kCircleDeg = 359;
// The search of a corner's turn starts at this step, each step halved down
// to the finest.
constexpr double kCornerTurnStepDeg = 2.0;
constexpr double kCornerTurnFinestDeg = 0.5;
// A turn whose coarsest steps leave it this far below the screening
// threshold is given up (9 in 10 are, in 2410 corner searches of 6
// touching and overlapping bench scenes). Measured, not a bound: there the
// finer steps raised no pose that passed by more than 0.1, though they
// raised some that still failed by up to 0.33; the same parts and poses
// were found on four type sets over 12 scenes with and without it.
constexpr double kCornerTurnGiveUp = 0.2;
// A settled pose explains a corner or arc of the blob when it puts the
// model's within this many pixels of it, turned within this many degrees
// (a corner's bisector is a few degrees off; an arc's middle is wherever
// the contact cut it: any turn within kArcSlideDeg).
constexpr double kExplainedPx = 3.0;
constexpr double kExplainedDeg = kCornerAngleSlackDeg;

}  // namespace

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
        // Edges that double back on each other (a hairpin) meet nowhere.
        if (std::abs(det) < kMinCornerSine) continue;
        const double along = (gap.x * out.y - gap.y * out.x) / det;
        const bool loop_convex = (turn > 0) == left_interior;
        corners->push_back({a.end + in * along, angleOf(u), u / std::hypot(u.x, u.y),
                            180.0 - std::abs(turn), loop.hole ? !loop_convex : loop_convex});
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

std::shared_ptr<const BlobSearchModel> searchOf(const PartModel& m) {
  return m.blob_search ? m.blob_search : makeBlobSearchModel(m);
}

BlobCorners::BlobCorners(std::vector<CornerAnchor> all)
    : corners(std::move(all)), by_opening(corners.size()) {
  for (size_t i = 0; i < by_opening.size(); ++i) by_opening[i] = i;
  std::sort(by_opening.begin(), by_opening.end(),
            [&](size_t a, size_t b) { return corners[a].opening_deg < corners[b].opening_deg; });
}

namespace {
// The poses proposed for one model in one blob (see propose), step by step:
// every model corner put on the blob's corners it may be (fromCorners), then
// every model arc on the blob's arcs of its radius (fromArcs). A pose that
// screens as well as a part verifies settles the anchors it explains.
class Proposer {
 public:
  Proposer(const PartModel& model, const BlobSearchModel& search, Anchors anchors,
           const BlobCorners& blob_corners, const std::vector<ArcAnchor>& image_arcs,
           const EdgeDistance& edges, std::vector<Candidate>* out)
      : model_(model),
        search_(search),
        anchors_(anchors),
        image_corners_(blob_corners.corners),
        by_opening_(blob_corners.by_opening),
        image_arcs_(image_arcs),
        edges_(edges),
        out_(out),
        threshold_(model.verify_percent / 100.0 - kCoarseSlack),
        // A corner's direction is a few degrees off (its edges are short):
        // the first look forgives that with a wider tolerance, and the turn
        // about the corner is then searched coarse to fine on the
        // screening samples.
        loose_(kLooseScreenFactor * model.edge_tolerance) {}

  // Each model corner on the image corners of about its opening angle.
  void fromCorners() {
    for (size_t mi = 0; mi < search_.corners.size(); ++mi) {
      if (!visits(mi, search_.quick_corners)) continue;
      const CornerAnchor& mc = search_.corners[mi];
      for (const size_t i : cornersLike(mc)) fromCorner(mi, image_corners_[i]);
    }
  }

  // An arc fixes where its centre goes; the turn about it lines up the two
  // arcs (kArcSlideDeg), scanned coarsely at a glance, and around each
  // promising step finely. The model's arc must turn the way the blob's arc
  // goes.
  void fromArcs() {
    for (size_t mi = 0; mi < search_.arcs.size(); ++mi) {
      if (!visits(mi, search_.quick_arcs)) continue;
      const ArcAnchor& ma = search_.arcs[mi];
      for (const auto& ia : image_arcs_) {
        if (std::abs(ia.radius - ma.radius) > std::max(2.0, 0.12 * ma.radius)) continue;
        if ((ia.sweep_deg > 0) != (ma.sweep_deg > 0)) continue;
        fromArc(mi, ia);
      }
    }
  }

 private:
  // Poses screened as well as a part verifies: a corner or an arc of the
  // blob that one of them already puts its model's corner or arc on has
  // nothing new to propose (every corner of a part that shows leads to the
  // same pose, which would be screened again and again).
  struct Settled {
    ImagePose pose;
    double c;
    double s;
  };

  // The pose putting model point `model_point` on `image_point` turned by
  // `angle`, scored on `samples`.
  Candidate screen(cv::Point2d model_point, cv::Point2d image_point, double angle,
                   const std::vector<BoundarySample>& samples) const {
    const double c = std::cos(angle * kRadPerDeg);
    const double s = std::sin(angle * kRadPerDeg);
    const cv::Point2d centre = image_point - rotate(model_point, c, s);
    const double score = verifyScore(samples, centre, angle, edges_, model_.edge_tolerance, false);
    return Candidate{&model_, ImagePose{centre, normalizeDeg(angle), false}, score, 0};
  }

  void settle(const Candidate& c) {
    if (c.score * 100 < model_.verify_percent) return;
    settled_.push_back(
        {c.pose, std::cos(c.pose.angle_deg * kRadPerDeg), std::sin(c.pose.angle_deg * kRadPerDeg)});
  }

  bool explained(cv::Point2d model_point, cv::Point2d image_point, double angle) const {
    return std::any_of(settled_.begin(), settled_.end(), [&](const Settled& q) {
      if (std::abs(signedDeg(q.pose.angle_deg - angle)) > kExplainedDeg) return false;
      const cv::Point2d at = q.pose.centre + rotate(model_point, q.c, q.s);
      return std::hypot(at.x - image_point.x, at.y - image_point.y) <= kExplainedPx;
    });
  }

  // Whether anchor `mi` is searched (see Anchors).
  bool visits(size_t mi, const std::vector<size_t>& quick_ones) const {
    if (anchors_ == Anchors::kAll) return true;
    const bool quick = std::find(quick_ones.begin(), quick_ones.end(), mi) != quick_ones.end();
    return quick == (anchors_ == Anchors::kQuick);
  }

  // The image corners model corner `mc` may be (a few in ten: about its
  // opening angle, as convex), in the blob's order.
  const std::vector<size_t>& cornersLike(const CornerAnchor& mc) {
    const auto first = std::lower_bound(
        by_opening_.begin(), by_opening_.end(), mc.opening_deg - kCornerAngleSlackDeg,
        [&](size_t i, double v) { return image_corners_[i].opening_deg < v; });
    visit_.clear();
    for (auto it = first; it != by_opening_.end() &&
                          image_corners_[*it].opening_deg <= mc.opening_deg + kCornerAngleSlackDeg;
         ++it) {
      if (image_corners_[*it].convex == mc.convex) visit_.push_back(*it);
    }
    std::sort(visit_.begin(), visit_.end());
    return visit_;
  }

  // Model corner `mi` on image corner `ic`: a first look at the bisectors'
  // turn, then the turn searched coarse to fine.
  void fromCorner(size_t mi, const CornerAnchor& ic) {
    const CornerAnchor& mc = search_.corners[mi];
    const double angle = ic.bisector_deg - mc.bisector_deg;
    if (explained(mc.at, ic.at, angle)) return;
    const auto start = firstLook(mi, ic, angle);
    if (!start) return;
    Candidate c = screen(mc.at, ic.at, *start, search_.sparse);
    for (double step = kCornerTurnStepDeg; step >= kCornerTurnFinestDeg; step /= 2) {
      if (step < kCornerTurnStepDeg && c.score < threshold_ - kCornerTurnGiveUp) break;
      const double at = c.pose.angle_deg;
      for (int k = -2; k <= 2; ++k) {
        if (k == 0 || (step < kCornerTurnStepDeg && std::abs(k) > 1)) continue;
        const Candidate n = screen(mc.at, ic.at, at + k * step, search_.sparse);
        if (n.score > c.score) c = n;
      }
    }
    if (c.score >= threshold_) out_->push_back(c);
    settle(c);
  }

  // The turn the search about corner `mi` on `ic` starts from: `angle`
  // where the first look at the corner's glance samples passes, or (a
  // quick search, just short of it) a few degrees either side of it; none
  // where neither passes.
  std::optional<double> firstLook(size_t mi, const CornerAnchor& ic, double angle) const {
    const CornerAnchor& mc = search_.corners[mi];
    // cos and sin of the difference of the two bisectors' directions.
    const double cosine = ic.bisector.x * mc.bisector.x + ic.bisector.y * mc.bisector.y;
    const double sine = ic.bisector.y * mc.bisector.x - ic.bisector.x * mc.bisector.y;
    const auto glances = [&](double c, double s, double needed) {
      return verifiesAtLeast(search_.corner_glance[mi], search_.glance_weight,
                             ic.at - rotate(mc.at, c, s), c, s, 1.0, edges_, loose_, needed);
    };
    const double needed = threshold_ - kGlanceSlack;
    if (glances(cosine, sine, needed)) return angle;
    // Just short of it, the bisector may be a few degrees off (a corner
    // between short or curved edges): see kGlanceNearMiss.
    if (anchors_ != Anchors::kQuick || !glances(cosine, sine, needed - kGlanceNearMiss))
      return std::nullopt;
    for (const double k : {-1.0, 1.0}) {
      const double a = (angle + k * kGlanceTurnDeg) * kRadPerDeg;
      if (glances(std::cos(a), std::sin(a), threshold_)) return angle + k * kGlanceTurnDeg;
    }
    return std::nullopt;
  }

  // Model arc `mi` on image arc `ia`: the coarse scan of the turn, then the
  // fine one about each of its peaks.
  void fromArc(size_t mi, const ArcAnchor& ia) {
    const ArcAnchor& ma = search_.arcs[mi];
    const double middle = ia.mid_deg - ma.mid_deg;
    if (explained(ma.centre, ia.centre, middle)) return;
    // A whole circle's ends are wherever its loop started: any turn.
    const bool circle = std::max(std::abs(ma.sweep_deg), std::abs(ia.sweep_deg)) >= kCircleDeg;
    const double half =
        circle ? 180.0
               : std::min(180.0, 0.5 * std::abs(std::abs(ma.sweep_deg) - std::abs(ia.sweep_deg)) +
                                     kArcSlideDeg);
    const double coarse = kCoarseScanStepPx / std::max(model_.radius, 1.0) / kRadPerDeg;
    const int steps = static_cast<int>(std::ceil(2 * half / coarse)) + 1;
    const double step = 2 * half / (steps - 1);
    scanArc(mi, ia, middle - half, step, steps);
    const double fine = kScanStepPx / std::max(model_.radius, 1.0) / kRadPerDeg;
    for (int k = 0; k < steps; ++k) {
      const double s = scan_[k];
      if (s < threshold_ - kGlanceSlack || (k > 0 && s < scan_[k - 1]) ||
          (k + 1 < steps && s <= scan_[k + 1])) {
        continue;
      }
      Candidate best;
      best.score = -1;
      const double at = middle - half + k * step;
      for (double a = at - step; a <= at + step; a += fine) {
        const Candidate c = screen(ma.centre, ia.centre, a, search_.sparse);
        if (c.score > best.score) best = c;
      }
      if (best.score >= threshold_) out_->push_back(best);
      settle(best);
    }
  }

  // The glance score of model arc `mi` on `ia` at `steps` turns `step`
  // apart from `from` (degrees), into scan_. A step whose glance cannot
  // reach the threshold is neither kept nor a better neighbour of one that
  // is: -1 stands for its score. The turn advances by a fixed rotation (no
  // sine and cosine per step).
  void scanArc(size_t mi, const ArcAnchor& ia, double from, double step, int steps) {
    const ArcAnchor& ma = search_.arcs[mi];
    scan_.resize(static_cast<size_t>(steps));
    const double start = from * kRadPerDeg;
    const double step_cos = std::cos(step * kRadPerDeg);
    const double step_sin = std::sin(step * kRadPerDeg);
    double turn_c = std::cos(start);
    double turn_s = std::sin(start);
    for (int k = 0; k < steps; ++k) {
      const double angle = from + k * step;
      const cv::Point2d centre = ia.centre - rotate(ma.centre, turn_c, turn_s);
      scan_[k] =
          verifiesAtLeast(search_.arc_glance[mi], search_.glance_weight, centre, turn_c, turn_s,
                          1.0, edges_, model_.edge_tolerance, threshold_ - kGlanceSlack)
              ? screen(ma.centre, ia.centre, angle, search_.glance).score
              : -1.0;
      const double next_c = turn_c * step_cos - turn_s * step_sin;
      turn_s = turn_s * step_cos + turn_c * step_sin;
      turn_c = next_c;
    }
  }

  const PartModel& model_;
  const BlobSearchModel& search_;
  Anchors anchors_;
  const std::vector<CornerAnchor>& image_corners_;
  const std::vector<size_t>& by_opening_;
  const std::vector<ArcAnchor>& image_arcs_;
  const EdgeDistance& edges_;
  std::vector<Candidate>* out_;
  double threshold_;
  double loose_;
  std::vector<Settled> settled_;
  std::vector<size_t> visit_;  // cornersLike's, kept for its capacity
  std::vector<double> scan_;   // scanArc's, likewise
};
}  // namespace

// Screens the poses proposed for one model (its own hand) in a blob.
void propose(const PartModel& model, const BlobSearchModel& search, Anchors anchors,
             const BlobCorners& blob_corners, const std::vector<ArcAnchor>& image_arcs,
             const EdgeDistance& edges, std::vector<Candidate>* out) {
  Proposer proposer(model, search, anchors, blob_corners, image_arcs, edges, out);
  proposer.fromCorners();
  proposer.fromArcs();
}

namespace {
// A pose of proposeAbout's first, coarse look: its score and where.
struct AboutPose {
  double score;
  cv::Point2d at;
  double turn_deg;
};
}  // namespace

void proposeAbout(const PartModel& model, const BlobSearchModel& search, cv::Point2d centre,
                  const EdgeDistance& edges, const EdgeDistance& wide, std::vector<Candidate>* out,
                  bool from_core) {
  const double threshold = model.verify_percent / 100.0 - kCoarseSlack;
  const double radius = std::max(model.radius, 1.0);
  const double loose = kLooseScreenFactor * model.edge_tolerance;
  // Where the reference point lies from `centre` at a turn (cos, sin): at
  // it, or, from the part's deepest core, less the core's middle turned.
  const cv::Point2d core = from_core ? search.core_middle : cv::Point2d();
  const auto fromCentre = [&](double c, double s) {
    return cv::Point2d(-(c * core.x - s * core.y), -(s * core.x + c * core.y));
  };
  const auto fromCentreAt = [&](double turn_deg) {
    const double a = turn_deg * kRadPerDeg;
    return fromCentre(std::cos(a), std::sin(a));
  };
  // The turns of a scan `step_px` apart at the model's rim, their cosines
  // and sines computed once.
  const auto turnsOf = [&](double step_px, double* step_deg) {
    const int steps = static_cast<int>(std::ceil(360.0 / (step_px / radius / kRadPerDeg)));
    *step_deg = 360.0 / steps;
    std::vector<cv::Point2d> turns(static_cast<size_t>(steps));
    for (int k = 0; k < steps; ++k) {
      const double a = k * *step_deg * kRadPerDeg;
      turns[static_cast<size_t>(k)] = {std::cos(a), std::sin(a)};
    }
    return turns;
  };
  // The first look: reference points kAboutCoarsePx apart, turns twice as
  // far apart as an arc's first scan, on the wide map at a tolerance that
  // much wider: a part's true pose is within half a step of one of these
  // either way, and screens there at the wider tolerance.
  static const std::vector<cv::Point2d> coarse_grid = aboutGrid(kAboutCoarsePx);
  double coarse_deg = 0;
  const std::vector<cv::Point2d> coarse_turns = turnsOf(2 * kCoarseScanStepPx, &coarse_deg);
  std::vector<cv::Point2d> coarse_shifts(coarse_turns.size());
  for (size_t k = 0; k < coarse_turns.size(); ++k) {
    coarse_shifts[k] = fromCentre(coarse_turns[k].x, coarse_turns[k].y);
  }
  const double wide_tolerance = loose + kAboutWidePx;
  // The first look's best pose (the first of poses that score alike: the
  // nearest to `centre`); a pose is scored in full only when it may be it.
  AboutPose first{threshold, centre, 0};
  bool seen = false;
  for (const cv::Point2d& offset : coarse_grid) {
    for (size_t k = 0; k < coarse_turns.size(); ++k) {
      const cv::Point2d at = centre + offset + coarse_shifts[k];
      const cv::Point2d& cs = coarse_turns[k];
      if (!verifiesAtLeast(search.glance, search.glance_weight, at, cs.x, cs.y, 1.0, wide,
                           wide_tolerance, threshold - kGlanceSlack) ||
          !verifiesAtLeast(search.sparse, search.sparse_weight, at, cs.x, cs.y, 1.0, wide,
                           wide_tolerance, first.score)) {
        continue;
      }
      const double turn = static_cast<double>(k) * coarse_deg;
      const double score = verifyScore(search.sparse, at, turn, wide, wide_tolerance, false);
      if (score < first.score || (seen && score == first.score)) continue;
      first = {score, at, turn};
      seen = true;
    }
  }
  if (!seen) return;
  // Then about it: reference points kAboutStepPx apart within half a
  // coarse step, turns an arc's first scan apart within a coarse step, at
  // the first look's loose tolerance.
  static const std::vector<cv::Point2d> fine_grid = aboutGrid(kAboutStepPx, kAboutCoarsePx / 2);
  const double fine_step = coarse_deg / 2;
  // The first look's reference point as `centre` would have put it at each
  // turn (the same at every turn but from the core).
  const cv::Point2d first_centre = first.at - fromCentreAt(first.turn_deg);
  double best = -1;
  double best_turn = 0;
  cv::Point2d best_at = centre;
  double best_off = 0;
  for (const cv::Point2d& offset : fine_grid) {
    for (int k = -2; k <= 2; ++k) {
      const double turn = first.turn_deg + k * fine_step;
      const cv::Point2d shift = from_core ? fromCentreAt(turn) : cv::Point2d();
      const cv::Point2d at = from_core ? first_centre + offset + shift : first.at + offset;
      const double off = cv::norm(at - (centre + shift));
      const double a = turn * kRadPerDeg;
      if (!verifiesAtLeast(search.glance, search.glance_weight, at, std::cos(a), std::sin(a), 1.0,
                           edges, loose, threshold - kGlanceSlack)) {
        continue;
      }
      const double score = verifyScore(search.sparse, at, turn, edges, loose, false);
      if (score < threshold) continue;
      // At the loose tolerance a sharp part screens whole a few pixels off
      // (4 px: the turn scan below then fails at the model's tolerance):
      // the share within that tolerance tells those poses apart; of poses
      // still alike, the nearest to `centre`.
      const double sharp =
          score + verifyScore(search.sparse, at, turn, edges, model.edge_tolerance, false);
      if (sharp > best || (sharp == best && off < best_off)) {
        best = sharp;
        best_turn = turn;
        best_at = at;
        best_off = off;
      }
    }
  }
  if (best < 0) return;
  const double fine = kScanStepPx / radius / kRadPerDeg;
  const cv::Point2d best_centre = best_at - fromCentreAt(best_turn);
  Candidate chosen{&model, ImagePose{best_at, 0, false}, -1, 0};
  for (double a = best_turn - fine_step; a <= best_turn + fine_step; a += fine) {
    const cv::Point2d at = from_core ? best_centre + fromCentreAt(a) : best_at;
    const double score = verifyScore(search.sparse, at, a, edges, model.edge_tolerance, false);
    if (score > chosen.score)
      chosen = Candidate{&model, ImagePose{at, normalizeDeg(a), false}, score, 0};
  }
  if (chosen.score >= threshold) out->push_back(chosen);
}
}  // namespace touching

using namespace touching;

std::shared_ptr<const BlobSearchModel> makeBlobSearchModel(const PartModel& model) {
  auto b = std::make_shared<BlobSearchModel>();
  anchorsOf(model.loops, &b->corners, &b->arcs);
  keepTelling(&b->corners, &b->arcs);
  b->sparse = sparseSamples(model.samples, kSparseSamples);
  b->glance = sparseSamples(model.samples, kGlanceSamples);
  for (const auto& g : b->glance) b->glance_weight += g.weight;
  for (const auto& g : b->sparse) b->sparse_weight += g.weight;
  const auto farthestFirst = [&](cv::Point2d from) {
    std::vector<BoundarySample> order = b->glance;
    std::stable_sort(order.begin(), order.end(),
                     [&](const BoundarySample& u, const BoundarySample& v) {
                       return cv::norm(u.point - from) > cv::norm(v.point - from);
                     });
    return order;
  };
  // The quick anchors: the sharpest corners and the longest arcs.
  const auto firstOf = [](size_t n, size_t count, const auto& before) {
    std::vector<size_t> order(n);
    for (size_t i = 0; i < n; ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), before);
    order.resize(std::min(n, count));
    return order;
  };
  b->quick_corners = firstOf(b->corners.size(), kQuickCorners, [&](size_t u, size_t v) {
    return std::abs(180 - b->corners[u].opening_deg) > std::abs(180 - b->corners[v].opening_deg);
  });
  const size_t quick_arcs = b->corners.size() < kQuickCorners ? kQuickArcs : 0;
  b->quick_arcs = firstOf(b->arcs.size(), quick_arcs, [&](size_t u, size_t v) {
    return b->arcs[u].length > b->arcs[v].length;
  });
  for (const auto& c : b->corners) b->corner_glance.push_back(farthestFirst(c.at));
  for (const auto& a : b->arcs) b->arc_glance.push_back(farthestFirst(a.centre));
  b->edges = edgeSamples(model, 1.0);
  std::vector<cv::Point2f> boundary;
  boundary.reserve(model.samples.size());
  for (const auto& sample : model.samples) boundary.emplace_back(sample.point);
  b->extent = extentOf(boundary);
  // The part drawn whole at its own origin, and its deepest core read as a
  // blob's is.
  if (!model.loops.empty()) {
    cv::Rect box;
    const cv::Mat drawn = drawnPart(model, {{0, 0}, 0, false}, 0, &box);
    if (const auto core = deepestCore(drawn, cv::Rect({0, 0}, drawn.size()))) {
      b->core_middle = core->middle + cv::Point2d(box.tl());
      b->core_depth_px = core->depth_px;
    }
  }
  return b;
}

}  // namespace picksight::vision
