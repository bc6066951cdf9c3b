// Parts inside merged blobs: the hypotheses of every model (see
// touching_parts_hypotheses.cpp) refined on the grey-level edges
// (touching_parts_edge_fit.cpp), each checked against its mirror image, then
// accepted best first where they fit the blob (their boundary on its edges
// or its body, not on the background) and not each other, two hypotheses
// of the same pixels settled by which lies on more of its edges. A quick
// search from each model's most telling anchors comes first; the full one
// goes on, model by model, only while the parts found leave some of the
// blob unexplained.
#include "picksight/vision/blob_search/touching_parts.hpp"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <map>
#include <optional>

#include "blob_search.hpp"
#include "picksight/common/angles.hpp"
#include "picksight/vision/segmentation/disc_morphology.hpp"
#include "picksight/vision/segmentation/row_runs.hpp"
#include "touching_parts_internal.hpp"

namespace picksight::vision {
namespace {
using namespace touching;
using picksight::angleDiffDeg;

constexpr int kMaxRefinedPerModel = 8;
// Poses refined per blob, for each part the blob can hold: the best
// screened hypotheses of all models, so that a blob costs about the same
// whatever the number of trained types.
constexpr int kRefinedPerPart = 12;
constexpr int kMaxRefinedPerBlob = 48;
// A mirror-image candidate that verifies within this of the direct one
// makes the handedness a question: where the two hands differ decides it
// (showsMirrorImage), and a part shown mirrored is not reported.
constexpr double kMirrorMargin = 0.03;
// A screened pose this close to one already refined is not refined again.
constexpr double kRefinedNearPx = 3.0;
constexpr double kRefinedNearDeg = 4.0;
// The edge fit of a screened pose: how far it looks for the edges at first,
// its passes.
constexpr double kEdgeSearchPx = 4.0;
constexpr int kEdgeIterations = 6;
// A fit whose coarse passes settle this close to a pose already refined
// ends there (the dense passes move a pose by hundredths of a pixel; two
// refined poses within a pixel and a degree are one).
constexpr double kConvergedPx = 0.5;
constexpr double kConvergedDeg = 0.5;
// The mirror image placed on a part is refined on the edges when it
// verifies within this of the margin before (a hypothesis a few pixels and
// degrees off loses that much at the rim, kCoarseSlack).
constexpr double kMirrorScreenSlack = 0.25;
// Parts that touch share at most their contact pixels; a part lying on
// another, up to a quarter of its outline hidden, shares up to a third of
// its area with it (0.31 at most of 193 parts taken in 12 overlapping
// bench scenes, sharp and blurred); two readings of the same pixels (a
// look-alike on a part, a pose twice) share most of them. A part lies in
// its blob.
constexpr double kMaxOverlap = 0.4;
constexpr double kMaxOutside = 0.06;

// A part lying partly under another shows less of its boundary: what is
// not on an edge lies on the other part's body. It then needs this much of
// its boundary on edges; down to kMinVisibleTight when what shows fits its
// edges as closely as a whole part does (kWholeFitRmsPx). A disc overlapped
// by a disc on either side shows 0.63 to 0.69 of its rim and fits it within
// 0.06 to 0.13 px (tests/data/scenes/detect_blob.png: 6 of the 13 discs
// found in its pile); a hand taken for its look-alike under another hand
// showed 0.69 at 1.08 px (the hands scan of overlapping_lookalikes_test,
// seed 55 blurred: confused at 0.6 without the fit's test).
constexpr double kMinVisible = 0.7;
constexpr double kMinVisibleTight = 0.6;
// The verified fraction the dense passes of the edge fit may still add.
constexpr double kUnsettledSlack = 0.1;
// The search of a blob ends once the parts found explain it whole: each
// fits its edges within this (pixels, rms; a part fits within a few tenths,
// a look-alike of another size or shape does not), and together they cover
// every pixel of the blob but a seam this wide (pixels) where the drawn
// outlines and the thresholded pixels disagree.
constexpr double kWholeFitRmsPx = 0.6;
constexpr int kSeamPx = 2;
// A part alone in its blob may be a few percent larger than the one taught
// (a coin 3 to 6 % wider, fitted 0.6 to 0.9 px rms: labelled touching on
// tests/data/scenes/coins.png): what it leaves of the blob is then a rim
// up to this wide (pixels), and not something it touches, which is as wide
// as a part.
constexpr int kAloneRimPx = 4;
// A corner or arc of the blob within this of what the parts found leave
// unexplained may belong to a part still to find (pixels).
constexpr int kRestAnchorPx = 6;
// A part's boundary is on the blob's edges or hidden under another part's
// body, never on the background, but where the model's primitives cut a
// sharp tip or notch by more than the edge tolerance: at most 1 % of the
// boundary on the benchmark's parts (a hand's fingertips, 0.98 %), blurred
// or not. A look-alike of another type placed on a part crosses it with
// 2.8 to 15 % (the hands of Kimia-99), however much of the rest lies on the
// part's edges, and may verify above the verify fraction there (0.83 to
// 0.85 on a hidden hand). Asked of every candidate but one that is its blob
// whole (the blob in it and it in the blob, kMaxOutside): a lone part the
// region tests failed on the pose its moments skewed, which the verify
// fraction alone judges, as the region tests do; a model that also accepts
// a similar type (a bar on a notched bar, 5 % across the notch) is left to
// the recognizer's screen across types. 2 % until the faint stretches of
// a low-contrast part (FaintPart) and boundary weights from the teach
// image's contrast: at 2.5 % the front-light benchmark's low contrast,
// overlapping, found 0.890 of its parts instead of 0.869 (10 scenes), every
// other figure the same, and the 60-seed hands scan confused none.
constexpr double kMaxOnBackground = 0.025;
// A stretch of a part narrower than twice this (pixels: no pixel of the
// part within kThinReachPx of the boundary sample is farther than this from
// the part's outline) is not counted as crossing the background: at 30 grey
// levels of contrast a lizard's finger and toe tips, 3 px across, are not in
// the frame at all (nor faint), and a lizard placed within 0.5 px, 0.81 to
// 0.97 of its boundary on edges, crossed on 2.6 to 3.3 % of it. With 2.5 px:
// front-light benchmark, low contrast, 8 scenes, touching 0.974 -> 0.983,
// overlapping 0.904 -> 0.930, precision still 1.000 on all eight lights; the
// look-alike hands scans (60 scenes sharp, blurred and at low contrast)
// confuse none (their one differing finger is 15 px across; not counting
// any crossing in runs under 20 samples instead confused 3 to 6). 3.5 px
// found more (0.991, 0.939), and would let more of a part's thin features
// go unseen. The cost: a part missing a feature under 5 px across (a broken
// pin) is not told from a whole one by this test where it touches another.
constexpr double kThinHalfWidthPx = 2.5;
constexpr int kThinReachPx = 4;
// A part in a blob shows some of its boundary on the blob's outline (or on
// a hole as large as kOutlineHoleShare of the smallest part: the surface
// between parts): at least kMinOnOutline of it. Placed on edges of small
// holes alone, it lies inside another part: the relief of a large coin
// (its face's highlights and shadows, holes in the mask) verified a
// smaller coin's rim there at 0.70 to 0.82 (tests/data/scenes/coins.png).
constexpr double kMinOnOutline = 0.25;
constexpr double kOutlineHoleShare = 0.25;
// In a blob the frame's edge cuts, a part placed is this many pixels clear
// of the edge (its outline's pixels): the edge blur of a part that reaches
// the last pixel is cut, and so is the part, by the rounding.
constexpr int kFrameClearancePx = 1;
// A blob the frame's edge cuts is searched only when this share of its
// outline steps in grey level (outlineSteps): a tray's wall, a streak of
// wood or a shadow running off the frame steps along its edge, a patch of
// the surface's own light does not. Measured (front-light benchmark at 30
// grey levels, on wood and photographed bricks, touching, 3 scenes each;
// the tests' walls and streaks): regions that held parts stepped along
// 0.61 to 1.0 of their outlines; a vignetted corner at 30 levels that the
// threshold speckled (424 holes, 73116 px) along 0.23, and searched, it
// cost 128 ms and gave a part where there was none. Blobs clear of the
// edge keep the lower bar (kMinOutlineSteppedShare): a part in them takes
// up more of their outline than the frame's edge leaves a part in these.
constexpr double kMinBorderSteppedShare = 0.35;

double boundaryLength(const PartModel& m) {
  double length = 0;
  for (const auto& loop : m.loops) {
    for (const auto& p : loop.primitives) length += p.length();
  }
  return length;
}

// A part's area less a seam of kSeamPx along its boundary (what the rest's
// erosion leaves of it).
double erodedArea(const PartModel& m) {
  return std::max(1.0, m.body.area - kSeamPx * boundaryLength(m));
}

// A part lies whole in its blob: what an erosion by kSeamPx leaves of the
// blob holds, in one piece, at least this much of the part: its area less
// its tolerance, less the seam where the square erosion reaches furthest
// (across a diagonal edge, kSeamPx times the square root of 2, so that a
// slender part lying diagonally is not taken for crumbs). A blob the
// frame's edge cuts is measured so before it is searched: where the
// threshold speckles a dark stretch of the surface at a low contrast
// (gravel's crevices, a vignetted corner), the mesh it makes runs off the
// frame and may step along half its outline, as a part's edge does, and
// its ragged outline and its holes give hundreds of corners to search
// from, for nothing; its strands are a few pixels wide, and the erosion
// leaves crumbs of them. Front-light benchmark, photographed gravel at 30
// grey levels, 3 scenes x 3 frames, the slowest LOCATE (p99) before and
// after: separated 31.8 -> 20.2 ms, touching 86.5 -> 65.0, overlapping
// 44.8 -> 32.9; the medians, and every part found and its pose, the same
// on all eight lights, bricks and gravel. A vignetted corner that the
// threshold took in as solid in places still holds pieces a part's size,
// and is searched (one at 30 levels: 11-33 ms of a LOCATE).
double leastCore(const PartModel& m) {
  return m.body.area * (1 - m.body.area_tolerance) - kSeamPx * std::sqrt(2.0) * boundaryLength(m);
}

// A part lies inside its blob (parts that touch or overlap make one blob
// of them all), so it is no longer and no wider than the blob, whatever
// their turns: a look-up that leaves out the models that cannot be there
// before any pose is proposed. The blob's outline runs through its
// boundary pixels' centres, half a pixel inside its edges either side; a
// slack of kExtentSlackPx for that and the threshold's place on a soft
// edge, and kExtentSlackShare of the part for a thin limb the threshold
// dropped at low contrast (placed all the same: see FaintPart).
constexpr double kExtentSlackPx = 4.0;
constexpr double kExtentSlackShare = 0.1;

bool fitsIn(const Extent& part, const Extent& blob) {
  const auto within = [](double p, double b) {
    return p <= b + kExtentSlackPx + kExtentSlackShare * p;
  };
  return within(part.diameter, blob.diameter) && within(part.width, blob.width);
}

// Calls f(k) for k in [0, n), on the cores the blob's own thread leaves
// idle. Nested in recognize()'s loop over regions (OpenCV's TBB arena),
// TBB lends a blob's models to threads that have no region left to take:
// the costliest blob (one a distractor touches, which no model explains
// and every model is searched in) is a fifth to a quarter of a touching
// frame's recognition, and on 8 cores and more the frame waits for it
// alone (picksight-bench-silhouettes --scaling). With one thread
// (cv::setNumThreads(1)), in turn here. Each f(k) writes its own slot; the
// callers then use the slots in model order, as the serial search did.
// Outside OpenCV's arena (it runs a loop of one region on the caller's
// thread), TBB's default arena would take every core of the machine: an
// arena of OpenCV's thread count keeps to cv::setNumThreads.
template <typename F>
void forEachModel(size_t n, F&& f) {
  const int allowed = cv::getNumThreads();
  if (n < 2 || allowed <= 1) {
    for (size_t k = 0; k < n; ++k) f(k);
    return;
  }
  const auto all = [&] { tbb::parallel_for(size_t{0}, n, [&](size_t k) { f(k); }); };
  if (tbb::this_task_arena::max_concurrency() <= allowed) {
    all();
  } else {
    tbb::task_arena arena(allowed);
    arena.execute(all);
  }
}

// The share of the model's boundary, placed at the pose, whose points
// satisfy `where` (image coordinates), by the samples' weights.
template <typename Where>
double boundaryShare(const PartModel& m, const ImagePose& pose, Where where) {
  const double c = std::cos(pose.angle_deg * kRadPerDeg);
  const double s = std::sin(pose.angle_deg * kRadPerDeg);
  const double flip = pose.mirrored ? -1.0 : 1.0;
  double total = 0;
  double share = 0;
  for (const auto& sample : m.samples) {
    total += sample.weight;
    if (where(pose.centre + rotate({sample.point.x, flip * sample.point.y}, c, s)))
      share += sample.weight;
  }
  return total > 0 ? share / total : 0;
}

bool samePose(const PartModel& m, const ImagePose& a, const ImagePose& b, double px, double deg) {
  if (a.mirrored != b.mirrored) return false;
  if (std::hypot(a.centre.x - b.centre.x, a.centre.y - b.centre.y) > px) return false;
  // A period of 0 (any turn looks the same): the angles always agree.
  return angleDiffDeg(a.angle_deg, b.angle_deg, m.symmetryDeg()) <= deg;
}

// The mirror image of a chiral model placed where it best covers the part
// at `direct`: turned by one of the angles where its complex moment lines
// up with the model's (2 phase / k + j 360 / k, as in training), the best
// verified of them refined on the grey-level edges. The hand of every part
// reported is decided against this one: the hypothesis search looks for
// each model's own hand only (searching the mirror image from the blob's
// corners and arcs as well cost a tenth of the search and changed no
// decision on the benchmark's type sets). Like any hypothesis it is refined
// only when it screens at `screen` (a fraction verified), and only to the
// end while it may still verify at `needed` (what the part's mirror image
// must reach): nullopt otherwise.
std::optional<Candidate> alignedMirror(const PartModel& m, const Region& region,
                                       const ImagePose& direct, const EdgeDistance& edges,
                                       double screen, double needed) {
  const int k = m.orientation_order;
  if (k <= 0 || m.body.mirror_symmetric) return std::nullopt;
  Candidate best;
  best.model = &m;
  best.score = -1;
  for (int j = 0; j < k; ++j) {
    const double angle = direct.angle_deg + 2 * m.orientation_phase_deg / k + j * 360.0 / k;
    const double score =
        verifyScore(m.samples, direct.centre, angle, edges, m.edge_tolerance, true);
    if (score > best.score) best = {&m, {direct.centre, angle, true}, score, 0, 0};
  }
  if (best.score < screen) return std::nullopt;
  // Settled where it verifies too little for the dense passes to lift it to
  // `needed`, and short of it unrefined too, it cannot be as good as the
  // part either way: no mirror image, and no dense passes.
  bool given_up = false;
  const auto worth = [&](const ImagePose& pose) {
    given_up = best.score < needed &&
               verifyScore(m.samples, pose.centre, pose.angle_deg, edges, m.edge_tolerance, true) <
                   needed - kUnsettledSlack;
    return !given_up;
  };
  const EdgeFit fit =
      refinePoseOnEdges(m, region, best.pose, kEdgeSearchPx, kEdgeIterations, worth);
  if (given_up) return std::nullopt;
  if (!fit.ok) return best;
  const double score =
      verifyScore(m.samples, fit.pose.centre, fit.pose.angle_deg, edges, m.edge_tolerance, true);
  if (score < best.score) return best;
  return Candidate{&m, fit.pose, score, fit.rms_px, fit.precise_length};
}

}  // namespace

std::vector<std::vector<cv::Point>> touching::placedOutline(const PartModel& m,
                                                            const ImagePose& pose) {
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
        poly.emplace_back(static_cast<int>(std::lround(r.x)), static_cast<int>(std::lround(r.y)));
      }
    }
    polys.push_back(std::move(poly));
  }
  return polys;
}

cv::Mat touching::drawnPart(const PartModel& m, const ImagePose& pose, int margin, cv::Rect* box) {
  const auto outline = placedOutline(m, pose);
  cv::Rect around;
  for (const auto& poly : outline) around |= cv::boundingRect(poly);
  *box = cv::Rect(around.x - margin, around.y - margin, around.width + 2 * margin + 1,
                  around.height + 2 * margin + 1);
  cv::Mat drawn(box->size(), CV_8UC1, cv::Scalar(0));
  cv::fillPoly(drawn, outline, cv::Scalar(255), cv::LINE_8, 0, -box->tl());
  return drawn;
}

namespace {

// Pixels two placed candidates share.
int sharedPixels(const Placed& a, const Placed& b) {
  const cv::Rect both = a.box & b.box;
  if (both.empty()) return 0;
  cv::Mat shared;
  cv::bitwise_and(a.drawn(both - a.box.tl()), b.drawn(both - b.box.tl()), shared);
  return cv::countNonZero(shared);
}

// Which of the placed candidates (best score first) are the blob's parts:
// best first, each where it does not overlap those already taken by more
// than parts can (kMaxOverlap). Two candidates that cannot both be parts
// explain the same pixels two ways: the one whose boundary lies on more
// of the blob's edges (EdgeFit::precise_length) is the part, whatever
// their scores, and the other waits for it to be refused. A similar
// outline of another type verifies within the edge tolerance on a part
// whose rest another hides, and is then first by its score; it lies on
// the part's edges for only short stretches.
// `mirrored(candidate)`: whether the part there shows the mirror image of
// the candidate's model; asked only of a candidate about to be taken.
template <typename MirrorTest>
std::vector<size_t> chooseParts(const std::vector<Placed>& placed, MirrorTest&& mirrored) {
  const size_t n = placed.size();
  // Rivals: pairs that cannot both be parts, whichever is taken first.
  std::vector<std::vector<size_t>> better(n);  // the rivals that explain more, per candidate
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j < n; ++j) {
      if (i == j || placed[j].candidate->precise <= placed[i].candidate->precise) continue;
      const int shared = sharedPixels(placed[i], placed[j]);
      if (shared > kMaxOverlap * std::max(placed[i].area, placed[j].area)) better[i].push_back(j);
    }
  }
  enum class State { kOpen, kTaken, kRefused };
  std::vector<State> state(n, State::kOpen);
  // The pixels taken, over the boxes of all.
  cv::Rect all;
  for (const auto& p : placed) all |= p.box;
  cv::Mat claimed(all.size(), CV_8UC1, cv::Scalar(0));
  const auto tryTake = [&](size_t i) {
    const Placed& p = placed[i];
    cv::Mat shared;
    cv::bitwise_and(p.drawn, claimed(p.box - all.tl()), shared);
    if (cv::countNonZero(shared) > kMaxOverlap * p.area || mirrored(*p.candidate)) {
      state[i] = State::kRefused;
      return;
    }
    state[i] = State::kTaken;
    cv::Mat claimed_here = claimed(p.box - all.tl());
    cv::bitwise_or(claimed_here, p.drawn, claimed_here);
  };
  // Whether a rival that explains more of candidate i's pixels is still
  // open or taken.
  const auto rivalIn = [&](size_t i) {
    return std::any_of(better[i].begin(), better[i].end(),
                       [&](size_t j) { return state[j] != State::kRefused; });
  };
  // Best score first; a candidate with an open rival that explains more
  // waits.
  std::vector<size_t> waiting;
  for (size_t i = 0; i < n; ++i) {
    if (rivalIn(i)) {
      waiting.push_back(i);
    } else {
      tryTake(i);
    }
  }
  // Then those that waited, the one explaining most first, each once every
  // rival that explains more has been refused.
  std::stable_sort(waiting.begin(), waiting.end(), [&](size_t a, size_t b) {
    return placed[a].candidate->precise > placed[b].candidate->precise;
  });
  for (const size_t i : waiting) {
    if (rivalIn(i)) {
      state[i] = State::kRefused;
    } else {
      tryTake(i);
    }
  }
  std::vector<size_t> taken;
  for (size_t i = 0; i < n; ++i) {
    if (state[i] == State::kTaken) taken.push_back(i);
  }
  return taken;
}

}  // namespace

namespace touching {

namespace {
// See FaintPart: the share of the contrast, and the least contrast (grey
// levels) worth reading. The surface's grain stays under a quarter of a
// 30-level contrast once smoothed over 3 x 3 pixels.
constexpr double kFaintShare = 0.35;
constexpr double kMinFaintContrast = 8;
// The blob's level is read this far inside its edge, the surface's in a
// ring this far outside it (pixels): clear of the edges' blur.
constexpr int kLevelInsetPx = 2;
constexpr int kRingFromPx = 3;
constexpr int kRingToPx = 7;

// The median grey level of `grey` where `mask` is set; -1 for none.
double medianWhere(const cv::Mat& grey, const cv::Mat& mask) {
  const int channels[] = {0};
  const int bins[] = {256};
  const float range[] = {0, 256};
  const float* ranges[] = {range};
  cv::Mat hist;
  cv::calcHist(&grey, 1, channels, mask, hist, 1, bins, ranges);
  const double total = cv::sum(hist)[0];
  if (total <= 0) return -1;
  double seen = 0;
  for (int i = 0; i < 256; ++i) {
    seen += hist.at<float>(i);
    if (seen >= total / 2) return i;
  }
  return 255;
}
}  // namespace

FaintPart::FaintPart(const Region& r, const cv::Mat& blob, cv::Rect blob_box) {
  if (r.grey.empty()) return;
  origin_ = r.grey_origin;
  const cv::Rect grey_box(origin_, r.grey.size());
  const cv::Rect both = blob_box & grey_box;
  if (both.empty()) return;
  cv::Mat mask(r.grey.size(), CV_8UC1, cv::Scalar(0));
  blob(both - blob_box.tl()).copyTo(mask(both - origin_));
  cv::Mat inside;
  cv::Mat near;
  cv::Mat ring;
  erodeDisc(mask, inside, kLevelInsetPx);
  dilateDisc(mask, near, kRingFromPx);
  dilateDisc(mask, ring, kRingToPx);
  ring.setTo(0, near);
  const double part = medianWhere(r.grey, inside);
  const double surface = medianWhere(r.grey, ring);
  if (part < 0 || surface < 0 || std::abs(surface - part) < kMinFaintContrast) return;
  cv::Mat smooth;
  cv::blur(r.grey, smooth, cv::Size(3, 3));
  // Darker than the surface by the share of the contrast (lighter, for a
  // blob lighter than its surface).
  const double level = surface - kFaintShare * (surface - part);
  cv::Mat faint;
  cv::compare(smooth, level, faint, surface > part ? cv::CMP_LE : cv::CMP_GE);
  // Only what joins the blob: a separate part nearby is as dark, and is
  // not a stretch of this one.
  cv::Mat joined = faint | mask;
  cv::Mat labels;
  const int count = cv::connectedComponents(joined, labels, 8, CV_32S);
  std::vector<uint8_t> of_blob(static_cast<size_t>(std::max(count, 1)), 0);
  for (int y = 0; y < mask.rows; ++y) {
    const uint8_t* m = mask.ptr<uint8_t>(y);
    const int* l = labels.ptr<int>(y);
    for (int x = 0; x < mask.cols; ++x) {
      if (m[x]) of_blob[static_cast<size_t>(l[x])] = 1;
    }
  }
  faint_ = cv::Mat(faint.size(), CV_8UC1, cv::Scalar(0));
  for (int y = 0; y < faint.rows; ++y) {
    const uint8_t* f = faint.ptr<uint8_t>(y);
    const int* l = labels.ptr<int>(y);
    uint8_t* out = faint_.ptr<uint8_t>(y);
    for (int x = 0; x < faint.cols; ++x) {
      if (f[x] && of_blob[static_cast<size_t>(l[x])]) out[x] = 255;
    }
  }
}

bool FaintPart::at(cv::Point2d p) const {
  if (faint_.empty()) return false;
  const int x = static_cast<int>(std::lround(p.x)) - origin_.x;
  const int y = static_cast<int>(std::lround(p.y)) - origin_.y;
  if (x < 0 || y < 0 || x >= faint_.cols || y >= faint_.rows) return false;
  return faint_.at<uint8_t>(y, x) != 0;
}

int FaintPart::countIn(const cv::Mat& drawn, cv::Rect box) const {
  const cv::Rect both = box & cv::Rect(origin_, faint_.size());
  if (faint_.empty() || both.empty()) return 0;
  cv::Mat faint;
  cv::bitwise_and(drawn(both - box.tl()), faint_(both - origin_), faint);
  return cv::countNonZero(faint);
}

BlobSearch::BlobSearch(const std::vector<Region>& regions, size_t index,
                       const std::vector<const PartModel*>& models, const EdgeDistance* built_edges,
                       const LoneRegionTest* read_rest)
    : region_(regions[index]), index_(index), read_rest_(read_rest) {
  // Nothing to place parts on in a patch of the surface's light.
  if (!outlineSteps(region_,
                    region_.touches_border ? kMinBorderSteppedShare : kMinOutlineSteppedShare)) {
    return;
  }
  const Extent blob_extent = extentOfOutline(region_.outer);
  // Of a blob the frame's edge cuts, the largest piece its erosion leaves
  // (kSeamPx; see leastCore).
  double core = region_.area;
  if (region_.touches_border && !region_.coverage.empty()) {
    cv::compare(region_.coverage, 0.5, blob_, cv::CMP_GE);
    cv::Mat eroded;
    cv::erode(
        blob_, eroded,
        cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * kSeamPx + 1, 2 * kSeamPx + 1)));
    cv::Mat labels, stats, centres;
    const int pieces = cv::connectedComponentsWithStats(eroded, labels, stats, centres, 8);
    core = 0;
    for (int k = 1; k < pieces; ++k) {
      core = std::max(core, static_cast<double>(stats.at<int>(k, cv::CC_STAT_AREA)));
    }
  }
  for (const PartModel* m : models) {
    // A part in the blob is no larger than the blob.
    if (m->loops.empty() || m->body.area * (1 - m->body.area_tolerance) > region_.area) continue;
    if (!fitsIn(searchOf(*m)->extent, blob_extent)) continue;
    if (leastCore(*m) > core) continue;
    fitting_.push_back(m);
    tolerance_ = std::max(tolerance_, m->edge_tolerance);
    conformity_ = std::min(conformity_, m->conformity);
  }
  if (fitting_.empty()) return;

  std::vector<std::vector<cv::Point>> contours{region_.outer};
  contours.insert(contours.end(), region_.hole_boundaries.begin(), region_.hole_boundaries.end());
  // Read at no more than the loose screening tolerance (and clipped there).
  if (!built_edges) own_edges_.emplace(edgeMap(kLooseScreenFactor * tolerance_));
  edges_ = built_edges ? built_edges : &*own_edges_;
  std::vector<std::vector<cv::Point2d>> loops2d;
  for (const auto& c : contours) loops2d.emplace_back(c.begin(), c.end());
  std::vector<CornerAnchor> image_corners;
  anchorsOf(fitLoops(loops2d, conformity_), &image_corners, &image_arcs_);
  // The search starts from all of the blob's anchors (narrowToRest turns it
  // to those near what the parts found leave unexplained).
  all_corners_.emplace(std::move(image_corners));
  corners_ = &*all_corners_;
  arcs_ = &image_arcs_;

  // The blob's pixels (over its box, image coordinates), which placed parts
  // are compared with.
  double smallest = region_.area;
  for (const PartModel* m : fitting_) smallest = std::min(smallest, m->body.area);
  blob_box_ = cv::Rect(region_.coverage_origin, region_.coverage.size());
  // The blob's pixels: made above already for a blob the frame cuts.
  if (blob_.empty()) cv::compare(region_.coverage, 0.5, blob_, cv::CMP_GE);
  coverage_.emplace(region_);
  blob_pixels_ = cv::countNonZero(blob_);
  const int parts = std::max(1, static_cast<int>(region_.area / std::max(smallest, 1.0)));
  budget_ = static_cast<size_t>(std::min(kMaxRefinedPerBlob, kRefinedPerPart * (parts + 1)));
  seam_ = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * kSeamPx + 1, 2 * kSeamPx + 1));
}

int BlobSearch::coveredIn(const cv::Mat& drawn, const cv::Rect& box) const {
  const cv::Rect both = box & blob_box_;
  if (both.empty()) return 0;
  cv::Mat covered;
  cv::bitwise_and(drawn(both - box.tl()), blob_(both - blob_box_.tl()), covered);
  return cv::countNonZero(covered);
}

std::vector<Candidate> BlobSearch::screen(const PartModel& model, Anchors anchors,
                                          bool* whole) const {
  std::vector<Candidate> proposed;
  propose(model, *searchOf(model), anchors, *corners_, *arcs_, *edges_, &proposed);
  std::stable_sort(proposed.begin(), proposed.end(),
                   [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
  std::vector<Candidate> screened;
  for (const auto& p : proposed) {
    if (static_cast<int>(screened.size()) >= kMaxRefinedPerModel) {
      if (whole) *whole = false;
      return screened;
    }
    const auto near = [&](const Candidate& q) { return samePose(model, p.pose, q.pose, 2.0, 3.0); };
    if (std::any_of(screened.begin(), screened.end(), near)) continue;
    screened.push_back(p);
  }
  if (whole) *whole = true;
  return screened;
}

double BlobSearch::onOutline(const PartModel& m, const ImagePose& pose) {
  if (!outline_) {
    // The blob's outer boundary and its holes that could be the surface
    // between parts (a quarter of the smallest part's area or more); not
    // the specks and relief a part's face shows as holes.
    double smallest = region_.area;
    for (const PartModel* f : fitting_) smallest = std::min(smallest, f->body.area);
    std::vector<std::vector<cv::Point>> contours{region_.outer};
    bool small_holes = false;
    for (const auto& hole : region_.hole_boundaries) {
      if (cv::contourArea(hole) >= kOutlineHoleShare * smallest) {
        contours.push_back(hole);
      } else {
        small_holes = true;
      }
    }
    // Without small holes the outline is every edge: the map the search
    // reads already.
    if (small_holes) {
      const int margin = static_cast<int>(std::ceil(tolerance_)) + 2;
      outline_.emplace(contours,
                       cv::Rect(region_.bbox.x - margin, region_.bbox.y - margin,
                                region_.bbox.width + 2 * margin, region_.bbox.height + 2 * margin),
                       tolerance_ + 1);
    } else {
      outline_.emplace();
    }
  }
  const EdgeDistance& outline = outline_->empty() ? *edges_ : *outline_;
  return boundaryShare(m, pose, [&](cv::Point2d p) { return outline.at(p) <= m.edge_tolerance; });
}

bool BlobSearch::crossesBackground(const PartModel& m, const ImagePose& pose) {
  // The share of boundary samples off the edges on the background, less
  // those on a faint part and those `thin` leaves out.
  const auto share = [&](const FaintPart* faint, const auto& thin) {
    return boundaryShare(m, pose, [&](cv::Point2d p) {
      return edges_->at(p) > m.edge_tolerance && coverage_->at(p) < 0.5 &&
             !(faint && faint->at(p)) && !thin(p);
    });
  };
  const auto none = [](cv::Point2d) { return false; };
  // The faint part only takes points out of the share: under the limit
  // without it, under it with it. It costs more than the rest of placing
  // (connected components over the blob's box), so it is made only for a
  // blob where a pose crosses without it, which evenly lit parts rarely do
  // (touching silhouettes, 15 types, recognition median: 9.3 ms before
  // the faint part, 14.6 ms with it made for every blob, 9.5-10.2 ms
  // made only when needed).
  if (share(nullptr, none) <= kMaxOnBackground) return false;
  if (!faint_) faint_.emplace(region_, blob_, blob_box_);
  if (share(&*faint_, none) <= kMaxOnBackground) return false;
  // Then without the part's thin stretches (kThinHalfWidthPx): the part
  // drawn at its pose, each pixel's distance from its outline.
  cv::Rect box;
  cv::Mat depth;
  cv::distanceTransform(drawnPart(m, pose, kThinReachPx, &box), depth, cv::DIST_L2,
                        cv::DIST_MASK_PRECISE);
  const auto thin = [&](cv::Point2d p) {
    const int x = static_cast<int>(std::lround(p.x)) - box.x;
    const int y = static_cast<int>(std::lround(p.y)) - box.y;
    const cv::Rect near =
        cv::Rect(x - kThinReachPx, y - kThinReachPx, 2 * kThinReachPx + 1, 2 * kThinReachPx + 1) &
        cv::Rect(0, 0, depth.cols, depth.rows);
    if (near.empty()) return false;
    double deepest = 0;
    cv::minMaxLoc(depth(near), nullptr, &deepest);
    return deepest < kThinHalfWidthPx;
  };
  return share(&*faint_, thin) > kMaxOnBackground;
}

bool BlobSearch::place(const Candidate& c) {
  const PartModel& m = *c.model;
  // Below the verify fraction, a part may be partly hidden (kMinVisible,
  // kMinVisibleTight).
  const bool verified = c.score * 100 >= m.verify_percent;
  if (!verified && c.score < kMinVisible &&
      (c.score < kMinVisibleTight || !(c.rms <= kWholeFitRmsPx)))
    return false;
  const bool crosses = crossesBackground(m, c.pose);
  if (!verified && crosses) return false;
  if (onOutline(m, c.pose) < kMinOnOutline) return false;
  cv::Rect box;
  cv::Mat drawn = drawnPart(m, c.pose, 0, &box);
  // In a blob cut by the frame's edge, only a part that lies inside the
  // frame, clear of its edge: one the edge cuts is not whole, and where
  // its outline runs along the edge, that line is the frame's, not an edge
  // of the part.
  if (region_.touches_border &&
      (box & cv::Rect(kFrameClearancePx, kFrameClearancePx,
                      region_.image_size.width - 2 * kFrameClearancePx,
                      region_.image_size.height - 2 * kFrameClearancePx)) != box) {
    return false;
  }
  Placed p{&c, box, std::move(drawn), 0};
  p.area = cv::countNonZero(p.drawn);
  if (p.area <= 0) return false;
  // The outline drawn whole covers its boundary's pixels (about half a
  // pixel all round more than the part's area): that seam lies off the
  // blob without the part lying off it. Counted in, it put a good pose of
  // a part 90 px long 6.8 % off its blob.
  const int seam = std::max(0, p.area - static_cast<int>(std::lround(m.body.area)));
  const int covered = coveredIn(p.drawn, box);
  int off_blob = p.area - covered;
  // Off the blob but where the grey levels show the part faint (a thin limb
  // the threshold dropped at low contrast): not off the part. Made only
  // for a pose that would otherwise be refused (see crossesBackground).
  if (off_blob - seam > kMaxOutside * p.area) {
    if (!faint_) faint_.emplace(region_, blob_, blob_box_);
    const cv::Rect both = box & blob_box_;
    cv::Mat drawn_off = p.drawn.clone();
    if (!both.empty()) drawn_off(both - box.tl()).setTo(0, blob_(both - blob_box_.tl()));
    off_blob -= faint_->countIn(drawn_off, box);
    if (off_blob - seam > kMaxOutside * p.area) return false;
  }
  // Crossing the background, only a candidate that is its blob whole
  // stays (kMaxOnBackground).
  if (crosses && blob_pixels_ - covered > kMaxOutside * p.area) return false;
  placed_.push_back(std::move(p));
  changed_ = true;
  return true;
}

void BlobSearch::refine(const std::vector<Candidate>& screened) {
  const EdgeDistance& edges = *edges_;
  for (const auto& p : screened) {
    const PartModel* m = p.model;
    // A screened pose next to one already refined converges to it: the
    // edge fit is the costliest step here.
    const auto refined_near = [&](const Candidate& q) {
      return q.model == m && samePose(*m, p.pose, q.pose, kRefinedNearPx, kRefinedNearDeg);
    };
    if (std::any_of(refined_.begin(), refined_.end(), refined_near)) continue;
    if (refinements_ >= budget_) return;
    ++refinements_;
    // Settled on a pose already refined (it would end as the same pose), or
    // on one too little of whose boundary lies on edges for a part, even a
    // partly hidden one: not worth the dense passes.
    const auto worth = [&](const ImagePose& pose) {
      const auto converged = [&](const Candidate& q) {
        return q.model == m && samePose(*m, pose, q.pose, kConvergedPx, kConvergedDeg);
      };
      if (std::any_of(refined_.begin(), refined_.end(), converged)) return false;
      return verifyScore(m->samples, pose.centre, pose.angle_deg, edges, m->edge_tolerance,
                         false) >= kMinVisibleTight - kUnsettledSlack;
    };
    const EdgeFit fit =
        refinePoseOnEdges(*m, region_, p.pose, kEdgeSearchPx, kEdgeIterations, worth);
    if (!fit.ok) continue;
    const auto same = [&](const Candidate& q) {
      return q.model == m && samePose(*m, fit.pose, q.pose, 1.0, 1.0);
    };
    if (std::any_of(refined_.begin(), refined_.end(), same)) continue;
    const double score = verifyScore(m->samples, fit.pose.centre, fit.pose.angle_deg, edges,
                                     m->edge_tolerance, false);
    refined_.push_back({m, fit.pose, score, fit.rms_px, fit.precise_length});
    place(refined_.back());
  }
}

// A part shown mirrored is not reported: the mirror image verifies about
// as well and where the hands differ fits better. Only asked of a
// candidate about to be taken (placing the mirror image costs an edge
// fit, made once per candidate).
bool BlobSearch::showsMirror(const Candidate& c) {
  const PartModel& m = *c.model;
  const auto as_good = [&](const Candidate& q) {
    return q.model == c.model &&
           std::hypot(q.pose.centre.x - c.pose.centre.x, q.pose.centre.y - c.pose.centre.y) <
               0.5 * m.radius &&
           q.score >= c.score - kMirrorMargin && showsMirrorImage(m, c.pose, q.pose, *edges_);
  };
  auto aligned = aligned_mirrors_.find(&c);
  if (aligned == aligned_mirrors_.end()) {
    aligned = aligned_mirrors_
                  .emplace(&c, alignedMirror(m, region_, c.pose, *edges_,
                                             c.score - kMirrorMargin - kMirrorScreenSlack,
                                             c.score - kMirrorMargin))
                  .first;
  }
  return aligned->second && as_good(*aligned->second);
}

// The parts among those placed: best first; among equal scores the closer
// fit to the grey-level edges.
void BlobSearch::choose() {
  changed_ = false;
  std::stable_sort(placed_.begin(), placed_.end(), [](const Placed& a, const Placed& b) {
    const Candidate& u = *a.candidate;
    const Candidate& v = *b.candidate;
    return u.score > v.score + 1e-9 || (std::abs(u.score - v.score) <= 1e-9 && u.rms < v.rms);
  });
  taken_ = chooseParts(placed_, [this](const Candidate& c) { return showsMirror(c); });
}

cv::Mat BlobSearch::unexplained() const {
  cv::Mat rest = blob_.clone();
  for (const size_t i : taken_) {
    const Placed& p = placed_[i];
    const cv::Rect both = p.box & blob_box_;
    if (!both.empty()) rest(both - blob_box_.tl()).setTo(0, p.drawn(both - p.box.tl()));
  }
  return rest;
}

bool BlobSearch::explainsWhole() const {
  if (taken_.empty()) return false;
  for (const size_t i : taken_) {
    if (placed_[i].candidate->rms > kWholeFitRmsPx) return false;
  }
  return coversBlob(kSeamPx);
}

bool BlobSearch::coversBlob(int seam_px) const {
  if (taken_.empty()) return false;
  cv::Mat rest = unexplained();
  // A seam runs along the blob's outline or a part's: more pixels than
  // fit in seams that long, and some piece is wider.
  double seam_length = static_cast<double>(region_.outer.size());
  for (const auto& h : region_.hole_boundaries) seam_length += static_cast<double>(h.size());
  for (const size_t i : taken_) {
    seam_length += static_cast<double>(searchOf(*placed_[i].candidate->model)->edges.size());
  }
  const int left = cv::countNonZero(rest);
  if (left == 0) return true;
  const int side = 2 * seam_px + 1;
  if (left > side * (seam_length + side)) return false;
  if (seam_px == kSeamPx) {
    cv::erode(rest, rest, seam_);
  } else {
    cv::erode(rest, rest, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(side, side)));
  }
  return cv::countNonZero(rest) == 0;
}

double BlobSearch::narrowToRest() {
  cv::Mat rest = unexplained();
  const double rest_area = std::max(1, cv::countNonZero(rest));
  // The parts to find lie in the rest, and their corners and arcs on its
  // rim (or where it meets the parts found): the full search starts from
  // those, not from the outlines of the parts found.
  cv::erode(rest, rest, seam_);
  if (cv::countNonZero(rest) == 0) return rest_area;
  // Whether any pixel of the rest lies in the square of `reach` about p
  // (the dilation of the rest by it, read at p): a sum over the integral
  // image.
  cv::Mat sums;
  cv::integral(rest, sums, CV_32S);
  const int reach = kSeamPx + kRestAnchorPx;
  const auto inRest = [&](cv::Point2d p) {
    const int x = static_cast<int>(std::lround(p.x)) - blob_box_.x;
    const int y = static_cast<int>(std::lround(p.y)) - blob_box_.y;
    const int x0 = std::clamp(x - reach, 0, rest.cols);
    const int x1 = std::clamp(x + reach + 1, 0, rest.cols);
    const int y0 = std::clamp(y - reach, 0, rest.rows);
    const int y1 = std::clamp(y + reach + 1, 0, rest.rows);
    if (x0 >= x1 || y0 >= y1) return false;
    return sums.at<int>(y1, x1) - sums.at<int>(y0, x1) - sums.at<int>(y1, x0) +
               sums.at<int>(y0, x0) >
           0;
  };
  std::vector<CornerAnchor> near_rest;
  for (const auto& c : all_corners_->corners) {
    if (inRest(c.at)) near_rest.push_back(c);
  }
  rest_corners_.emplace(std::move(near_rest));
  rest_arcs_.clear();
  for (const auto& a : image_arcs_) {
    const double mid = a.mid_deg * kRadPerDeg;
    if (inRest(a.centre + a.radius * cv::Point2d(std::cos(mid), std::sin(mid))))
      rest_arcs_.push_back(a);
  }
  corners_ = &*rest_corners_;
  arcs_ = &rest_arcs_;
  return rest_area;
}

void BlobSearch::fullSearch(std::vector<std::pair<double, size_t>> order) {
  // Rounds while each finds more and the budget lasts: a screening keeps
  // kMaxRefinedPerModel poses, and a pile of one type (20 touching discs of
  // a photograph) holds more parts than that; each round starts from what
  // the parts found so far leave unexplained.
  for (;;) {
    const size_t found_before = taken_.size();
    // With parts found, the rest of the blob is most likely one part more:
    // the models closest to its area first. Otherwise those the quick
    // search saw most of.
    if (!taken_.empty()) {
      const double rest_area = narrowToRest();
      for (auto& entry : order) {
        entry.first = -std::abs(fitting_[entry.second]->body.area - rest_area) / rest_area;
      }
    }
    std::stable_sort(order.begin(), order.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    // The round's screens read the anchors narrowed above and the edges
    // only: as many at once as there are threads, then refined in order
    // until the blob is explained (at most a thread's worth screened in
    // vain; one by one on one thread).
    const size_t batch = static_cast<size_t>(std::max(1, cv::getNumThreads()));
    std::vector<std::vector<Candidate>> screened;
    for (size_t start = 0; start < order.size(); start += batch) {
      const size_t n = std::min(batch, order.size() - start);
      screened.assign(n, {});
      // A model whose quick screening kept every pose it found is screened
      // from its other anchors only: its quick ones lead to those poses
      // again (the anchors narrowed to the rest are among those it read),
      // all refined already. Front-light benchmark, textured belt, touching,
      // 3 scenes: 8 % fewer pairs of anchors screened, LOCATE median 2 %
      // less; every part found and placed the same on 7 lights and the 15
      // standard types.
      forEachModel(n, [&](size_t k) {
        const size_t model = order[start + k].second;
        screened[k] =
            screen(*fitting_[model], quick_whole_[model] ? Anchors::kBeyondQuick : Anchors::kAll);
      });
      for (size_t k = 0; k < n; ++k) {
        refine(screened[k]);
        if (!changed_) continue;
        choose();
        if (explainsWhole()) return;
        // Beside a whole untaught copy of a type, nothing more to look for;
        // where the rest is one part, it is taken from there.
        if (settleRest()) return;
      }
    }
    if (taken_.size() <= found_before || refinements_ >= budget_) return;
  }
}

// What the rest's middle is searched for: models whose area is within
// these multiples of the rest's largest piece (the rest is a part less what
// another part hides of it, up to kMaxOverlap of its area, less the seam;
// or a part and a sliver of a neighbour the parts found leave over).
constexpr double kRestMinArea = 0.7;
constexpr double kRestMaxArea = 2.0;

EdgeDistance BlobSearch::edgeMap(double reach) const {
  std::vector<std::vector<cv::Point>> contours{region_.outer};
  contours.insert(contours.end(), region_.hole_boundaries.begin(), region_.hole_boundaries.end());
  const int margin = static_cast<int>(std::ceil(reach)) + 2;
  return EdgeDistance(contours,
                      cv::Rect(region_.bbox.x - margin, region_.bbox.y - margin,
                               region_.bbox.width + 2 * margin, region_.bbox.height + 2 * margin),
                      reach);
}

namespace {
// A piece of the rest the middle search is run about: its middle and area
// (splitAtNecks gives the middle over the blob's box, searchRestMiddle over
// the image).
struct RestPiece {
  cv::Point2d middle;
  double area = 0;
};

// The pieces of `piece` (a mask over the blob's box, one 8-connected piece,
// its bounding box `box`) that meet at necks: two parts whose corners the
// anchors did not lead to (under a front light at 30 grey levels of
// contrast, both parts of a touching pair were missed so: the search about
// the middle of the two, between them, found neither). Its cores deep
// inside, at the shallowest depth of kSplitDepths (shares of its deepest)
// that parts it into two or more cores of at least kMinCoreShare of the
// largest one, grown back over the piece, each pixel to its nearest core;
// the kMaxSplitPieces largest. Empty when no depth parts it.
constexpr std::array<double, 6> kSplitDepths = {0.15, 0.25, 0.35, 0.45, 0.55, 0.65};
// A piece's deepest core: its pixels deeper than this share of its deepest
// (deepestCore). Half: a thinner part joined to a thicker one (a
// limb of another lying over it) has none of its own there.
constexpr double kCoreDepthShare = 0.5;
// A blob's deepest core is a part's own when the blob is that deep where
// the part is (less the seam the rest is eroded by), within this share of
// the part's depth and two reduced pixels: parts joined or overlapping
// deepen the union only where they meet, and a part thinner or thicker than
// the core is not the one that holds it.
constexpr double kCoreDepthSlack = 0.2;
constexpr double kMinCoreShare = 0.1;
constexpr size_t kMaxSplitPieces = 3;
constexpr double kSplitPixels = 128 * 128;
// A piece split off at a neck is a part's pixels less the seam, and more or
// less of the neck: the models whose area less the seam is within this
// share of it, the nearest few (each costs a turn scan about the piece's
// middle).
constexpr double kSplitAreaSlack = 0.15;
constexpr size_t kSplitModelsPerPiece = 2;

// A piece's depth (each pixel's distance from its outline), read at a
// scale of at most kSplitPixels: the middles found on it are searched about
// within a dozen pixels (proposeAbout), and at full scale the transforms
// and labellings that read it took 9 ms on a blob of two large parts.
// `small`: the reduced piece with a rim of background (so that the depth is
// measured from every side), `depth` over it; a reduced pixel i (past the
// rim) covers the piece's pixels from (i - 1) * scale on.
struct PieceDepth {
  int scale = 1;
  cv::Mat small;
  cv::Mat depth;
  // A reduced pixel's middle, back over the image.
  cv::Point2d toImage(cv::Point2d at, const cv::Rect& box) const {
    const double half = 0.5 * (scale - 1);
    return {box.x + (at.x - 1) * scale + half, box.y + (at.y - 1) * scale + half};
  }
};

PieceDepth depthOf(const cv::Mat& piece, const cv::Rect& box) {
  PieceDepth d;
  d.scale = std::max(1, static_cast<int>(std::ceil(std::sqrt(box.area() / kSplitPixels))));
  cv::resize(piece(box), d.small,
             cv::Size((box.width + d.scale - 1) / d.scale, (box.height + d.scale - 1) / d.scale), 0,
             0, cv::INTER_AREA);
  cv::compare(d.small, 127, d.small, cv::CMP_GT);
  cv::copyMakeBorder(d.small, d.small, 1, 1, 1, 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::distanceTransform(d.small, d.depth, cv::DIST_L2, cv::DIST_MASK_3, CV_32F);
  return d;
}

std::vector<RestPiece> splitAtNecks(const cv::Mat& piece, const cv::Rect& box) {
  const PieceDepth reduced = depthOf(piece, box);
  const int scale = reduced.scale;
  const cv::Mat& small = reduced.small;
  const cv::Mat& depth = reduced.depth;
  double deepest = 0;
  cv::minMaxLoc(depth, nullptr, &deepest);
  for (const double share : kSplitDepths) {
    cv::Mat cores;
    cv::compare(depth, share * deepest, cores, cv::CMP_GT);
    cv::Mat labels;
    cv::Mat stats;
    cv::Mat centroids;
    const int n = cv::connectedComponentsWithStats(cores, labels, stats, centroids, 8, CV_32S);
    int largest = 0;
    for (int k = 1; k < n; ++k) largest = std::max(largest, stats.at<int>(k, cv::CC_STAT_AREA));
    std::vector<int> kept;  // labels of the cores large enough
    for (int k = 1; k < n; ++k) {
      if (stats.at<int>(k, cv::CC_STAT_AREA) >= kMinCoreShare * largest) kept.push_back(k);
    }
    if (kept.size() < 2) continue;
    // Every pixel of the piece to its nearest kept core.
    cv::Mat seeds = cv::Mat::zeros(small.size(), CV_8UC1);
    for (const int k : kept) seeds.setTo(255, labels == k);
    cv::Mat nearest;
    cv::Mat voronoi;
    cv::distanceTransform(~seeds, nearest, voronoi, cv::DIST_L2, cv::DIST_MASK_3,
                          cv::DIST_LABEL_CCOMP);
    double labels_used = 0;
    cv::minMaxLoc(voronoi, nullptr, &labels_used);
    std::vector<cv::Moments> grown(static_cast<size_t>(labels_used) + 1);
    for (int y = 0; y < small.rows; ++y) {
      const uint8_t* in = small.ptr<uint8_t>(y);
      const int* to = voronoi.ptr<int>(y);
      for (int x = 0; x < small.cols; ++x) {
        if (!in[x]) continue;
        cv::Moments& m = grown[static_cast<size_t>(to[x])];
        m.m00 += 1;
        m.m10 += x;
        m.m01 += y;
      }
    }
    // Back to the rest's box.
    std::vector<RestPiece> out;
    for (const cv::Moments& m : grown) {
      if (m.m00 <= 0) continue;
      out.push_back({reduced.toImage({m.m10 / m.m00, m.m01 / m.m00}, box), m.m00 * scale * scale});
    }
    std::stable_sort(out.begin(), out.end(),
                     [](const RestPiece& a, const RestPiece& b) { return a.area > b.area; });
    if (out.size() > kMaxSplitPieces) out.resize(kMaxSplitPieces);
    return out;
  }
  return {};
}
}  // namespace

std::optional<DeepestCore> deepestCore(const cv::Mat& piece, const cv::Rect& box) {
  if (box.empty()) return std::nullopt;
  const PieceDepth reduced = depthOf(piece, box);
  double deepest = 0;
  cv::Point at;
  cv::minMaxLoc(reduced.depth, nullptr, &deepest, nullptr, &at);
  if (deepest <= 0) return std::nullopt;
  cv::Mat core;
  cv::compare(reduced.depth, kCoreDepthShare * deepest, core, cv::CMP_GT);
  cv::Mat labels;
  cv::Mat stats;
  cv::Mat middles;
  cv::connectedComponentsWithStats(core, labels, stats, middles, 8, CV_32S);
  const int own = labels.at<int>(at);
  const cv::Point2d middle(middles.at<double>(own, 0), middles.at<double>(own, 1));
  return DeepestCore{reduced.toImage(middle, box), deepest * reduced.scale,
                     static_cast<double>(reduced.scale)};
}

void BlobSearch::searchAbout(const std::vector<std::pair<const PartModel*, cv::Point2d>>& sized,
                             bool from_core) {
  if (sized.empty()) return;
  if (!about_map_) about_map_ = edgeMap(kLooseScreenFactor * tolerance_ + kAboutWidePx);
  const EdgeDistance& wide = *about_map_;
  std::vector<std::vector<Candidate>> each(sized.size());
  forEachModel(sized.size(), [&](size_t k) {
    const PartModel& m = *sized[k].first;
    proposeAbout(m, *searchOf(m), sized[k].second, *edges_, wide, &each[k], from_core);
  });
  std::vector<Candidate> proposed;
  for (const auto& e : each) proposed.insert(proposed.end(), e.begin(), e.end());
  std::stable_sort(proposed.begin(), proposed.end(),
                   [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
  refine(proposed);
}

void BlobSearch::searchRestMiddle() {
  cv::Mat rest = unexplained();
  cv::erode(rest, rest, seam_);
  // The pieces, from their outlines: labelling the pieces' pixels took
  // eight times as long on a blob of two parts (0.5 ms).
  std::vector<std::vector<cv::Point>> outlines;
  cv::findContours(rest, outlines, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  std::vector<std::pair<cv::Moments, size_t>> pieces;  // largest first
  for (size_t i = 0; i < outlines.size(); ++i) {
    const cv::Moments m = cv::moments(outlines[i]);
    if (m.m00 > 0) pieces.emplace_back(m, i);
  }
  if (pieces.empty()) return;
  std::stable_sort(pieces.begin(), pieces.end(),
                   [](const auto& u, const auto& v) { return u.first.m00 > v.first.m00; });
  const auto middleOf = [&](const cv::Moments& m) {
    return cv::Point2d(blob_box_.x + m.m10 / m.m00, blob_box_.y + m.m01 / m.m00);
  };
  const double area = pieces.front().first.m00;
  // The models of the largest piece's size, each turned about its middle
  // (all at once, gathered in model order), on the map proposeAbout's first
  // look reads.
  std::vector<std::pair<const PartModel*, cv::Point2d>> sized;
  for (const PartModel* m : fitting_) {
    if (m->body.area >= kRestMinArea * area && m->body.area <= kRestMaxArea * area)
      sized.emplace_back(m, middleOf(pieces.front().first));
  }
  searchAbout(sized);
  if (changed_) choose();
  if (!taken_.empty()) return;
  // Nothing taken about the middle of the largest piece: where another
  // part lies joined to it, or over it, and no part the blob holds was
  // found, that middle lies between them, tens of pixels from either (a
  // star under a smaller bird of no taught type, at 30 grey levels of
  // contrast: 43 px). The deepest core is still the thicker part's own,
  // and a part holding it lies with its own deepest core there: the same
  // models are searched about it, each with its reference point where its
  // core's middle puts it at every turn. Front-light benchmark, overlapping,
  // 14 unseen types, 14 scenes: parts found at 30 grey levels 0.961 ->
  // 0.976, glossy 0.990 -> 0.995, clean 0.985 -> 0.990; 5 scenes wood 0.987
  // -> 1.000, gravel 0.821 -> 0.846; the 15 standard types (8 scenes) and
  // touching parts the same; nothing falsely reported.
  const size_t largest = pieces.front().second;
  const cv::Rect largest_box = cv::boundingRect(outlines[largest]);
  cv::Mat piece = cv::Mat::zeros(rest.size(), CV_8UC1);
  cv::drawContours(piece, outlines, static_cast<int>(largest), cv::Scalar(255), cv::FILLED);
  cv::bitwise_and(piece, rest, piece);
  if (const auto core = deepestCore(piece, largest_box)) {
    const cv::Point2d at = core->middle + cv::Point2d(blob_box_.tl());
    const cv::Point2d middle = middleOf(pieces.front().first);
    std::vector<std::pair<const PartModel*, cv::Point2d>> from_core;
    for (const auto& [m, unused] : sized) {
      const BlobSearchModel& search = *searchOf(*m);
      // A model whose reference point lies, at every turn, within a step of
      // the about search's grid (kAboutStepPx) of the middle searched
      // already was searched there.
      if (cv::norm(at - middle) + cv::norm(search.core_middle) <= kAboutStepPx) continue;
      // The core is the part's own only as deep as the part is (kCoreDepthSlack).
      const double slack = kCoreDepthSlack * search.core_depth_px + 2 * core->step_px;
      if (std::abs(core->depth_px + kSeamPx - search.core_depth_px) > slack) continue;
      from_core.emplace_back(m, at);
    }
    searchAbout(from_core, true);
  }
  // Nothing of the blob explained, nor taken about those middles: the parts
  // the blob may hold elsewhere, each about its own middle, a whole part
  // each (the models nearest its size, kSplitAreaSlack): the rest's other
  // pieces (two parts touching at a point part under the seam's erosion,
  // and the largest piece was the one no model explains), and, where the
  // largest has room for two parts, the pieces it parts into at its necks.
  // Front-light benchmark, 3 scenes of 20 parts a condition, clean,
  // textured, 30 grey levels, wood: touching at 30 levels 0.978 of the
  // parts found before, 1.000 with both; on the textured belt 0.991 and
  // 1.000; overlapping at 30 levels 0.963 and 0.967, clean 0.988 and 0.992;
  // nothing falsely reported, every other figure the same.
  if (changed_) choose();
  if (!taken_.empty()) return;
  std::vector<RestPiece> parts;
  for (size_t k = 1; k < pieces.size() && parts.size() < kMaxSplitPieces; ++k) {
    parts.push_back({middleOf(pieces[k].first), pieces[k].first.m00});
  }
  double smallest = area;
  for (const PartModel* m : fitting_) {
    smallest = std::min(smallest, m->body.area * (1 - m->body.area_tolerance));
  }
  if (area >= 2 * smallest) {
    for (RestPiece part : splitAtNecks(piece, largest_box)) {
      part.middle += cv::Point2d(blob_box_.tl());
      parts.push_back(part);
    }
  }
  sized.clear();
  for (const RestPiece& part : parts) {
    std::vector<std::pair<double, const PartModel*>> near;  // (|area off|, model)
    for (const PartModel* m : fitting_) {
      const double off = std::abs(part.area / erodedArea(*m) - 1);
      if (off <= kSplitAreaSlack) near.emplace_back(off, m);
    }
    std::stable_sort(near.begin(), near.end(),
                     [](const auto& u, const auto& v) { return u.first < v.first; });
    if (near.size() > kSplitModelsPerPiece) near.resize(kSplitModelsPerPiece);
    for (const auto& [off, m] : near) sized.emplace_back(m, part.middle);
  }
  searchAbout(sized);
}

namespace {
// The share of the outline of `mask` (its pixels with a 4-neighbour off
// it; `origin`: its top-left pixel in the image) that lies within `reach`
// of the edges `edges` maps; 0 for an empty mask. Sixteen pixels a test
// where the outline is not: most of a mask's box is inside it or off it.
double outlineShareOn(const cv::Mat& mask, cv::Point origin, const EdgeDistance& edges,
                      double reach) {
  cv::Mat outline;
  cv::erode(mask, outline, cv::getStructuringElement(cv::MORPH_CROSS, cv::Size(3, 3)),
            cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::subtract(mask, outline, outline);
  const EdgeDistance::Within within = edges.withinOf(reach);
  int all = 0;
  int on = 0;
  forEachSetPixel(outline, [&](int x, int y) {
    ++all;
    on += edges.isWithin({static_cast<double>(origin.x + x), static_cast<double>(origin.y + y)},
                         within)
              ? 1
              : 0;
  });
  return all > 0 ? static_cast<double>(on) / all : 0.0;
}
}  // namespace

// What the parts taken leave is tested as one whole object when its
// largest piece holds at least this share of it (after an opening by the
// seam: the slivers along the parts' drawn outlines are no object).
constexpr double kWholeRestShare = 0.95;
// ... and when at least this share of its outline (opened) lies on the
// blob's (within kOnBlobOutlinePx): an object touching the parts found,
// not one they lie over and cut, where the test cannot succeed. Five
// lights of the front-light benchmark and the silhouette benchmark's 15
// types, 3 scenes each: rests that touch read 0.94-1.00, the copies among
// them 0.978-1.000; rests an overlapping part cuts 0.70-0.99, 99 of 104
// under 0.97 (the copies among them, 0.92-0.93, are left to the search).
// With no gate the test took 2-4 % of an overlapping frame's time.
constexpr double kWholeOutlineShare = 0.97;
constexpr double kOnBlobOutlinePx = 2.5;

LoneReading BlobSearch::readRest() {
  if (!read_rest_ || taken_.empty() || region_.touches_border) return {};
  // Asked again with the same parts taken, the reading is the same.
  if (rest_read_ && rest_read_->taken == taken_) return rest_read_->reading;
  rest_read_ = RestRead{taken_, {}, {}};
  // Read over the box of what is left, with room for the opening (the
  // same there as over the blob's box): where a part lies over another,
  // that is a part's box, not the blob's.
  const cv::Mat unexplained_box = unexplained();
  const cv::Rect held = cv::boundingRect(unexplained_box);
  if (held.empty()) return {};
  const int margin = kSeamPx + 1;
  const cv::Rect box = (held + cv::Size(2 * margin, 2 * margin) - cv::Point(margin, margin)) &
                       cv::Rect({0, 0}, unexplained_box.size());
  const cv::Mat left = unexplained_box(box);
  const cv::Point origin = blob_box_.tl() + box.tl();  // of `rest`, in the image
  // The slivers along the parts' drawn outlines opened away; what is left
  // is an object of its own only where its outline is the blob's.
  cv::Mat rest;
  cv::morphologyEx(left, rest, cv::MORPH_OPEN, seam_);
  if (outlineShareOn(rest, origin, *edges_, kOnBlobOutlinePx) < kWholeOutlineShare) return {};
  std::vector<std::vector<cv::Point>> contours;
  std::vector<cv::Vec4i> hierarchy;
  cv::findContours(rest, contours, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE, origin);
  int largest = -1;
  double largest_area = 0;
  for (int i = 0; i < static_cast<int>(contours.size()); ++i) {
    if (hierarchy[static_cast<size_t>(i)][3] >= 0) continue;  // a hole
    const double a = cv::contourArea(contours[static_cast<size_t>(i)]);
    if (a > largest_area) {
      largest_area = a;
      largest = i;
    }
  }
  if (largest < 0) return {};
  // The piece, its holes cleared, over its own box (as a region's coverage).
  Region piece;
  piece.outer = contours[static_cast<size_t>(largest)];
  for (int h = hierarchy[static_cast<size_t>(largest)][2]; h >= 0;
       h = hierarchy[static_cast<size_t>(h)][0]) {
    piece.hole_boundaries.push_back(contours[static_cast<size_t>(h)]);
  }
  piece.holes = static_cast<int>(piece.hole_boundaries.size());
  piece.bbox = cv::boundingRect(piece.outer);
  cv::Mat own = cv::Mat::zeros(piece.bbox.size(), CV_8UC1);
  cv::drawContours(own, std::vector<std::vector<cv::Point>>{piece.outer}, 0, cv::Scalar(255),
                   cv::FILLED, cv::LINE_8, cv::noArray(), 0, -piece.bbox.tl());
  for (const auto& hole : piece.hole_boundaries) {
    cv::drawContours(own, std::vector<std::vector<cv::Point>>{hole}, 0, cv::Scalar(0), cv::FILLED,
                     cv::LINE_8, cv::noArray(), 0, -piece.bbox.tl());
  }
  cv::bitwise_and(own, rest(piece.bbox - origin), own);
  const int pixels = cv::countNonZero(own);
  if (pixels <= 0 || pixels < kWholeRestShare * cv::countNonZero(rest)) return {};
  piece.area = pixels;
  piece.moments = cv::moments(own, true);
  piece.centroid = cv::Point2d(piece.bbox.x + piece.moments.m10 / piece.moments.m00,
                               piece.bbox.y + piece.moments.m01 / piece.moments.m00);
  own.convertTo(piece.coverage, CV_32F, 1.0 / 255);
  piece.coverage_origin = piece.bbox.tl();
  piece.image_size = region_.image_size;
  rest_read_->reading = (*read_rest_)(piece);
  rest_read_->centre = piece.centroid;
  return rest_read_->reading;
}

bool BlobSearch::settleRest() {
  const LoneReading rest = readRest();
  if (rest.kind == LoneReading::Kind::kCopy) return true;
  if (rest.kind != LoneReading::Kind::kPart) return false;
  // Only a model the blob search may place (one that fits in the blob).
  if (std::find(fitting_.begin(), fitting_.end(), rest.model) == fitting_.end()) return false;
  Candidate at_rest;
  at_rest.model = rest.model;
  at_rest.pose = {rest_read_->centre, rest.angle_deg, false};
  refine({at_rest});
  if (changed_) choose();
  return explainsWhole();
}

std::vector<Match> BlobSearch::run() {
  if (fitting_.empty()) return {};
  // First a quick search of every model, from its most telling corners and
  // arc: the parts that show whole are mostly found there. Then, while the
  // parts found do not explain the blob whole, the full search of each model,
  // those the quick search found something of first.
  // The screens read the blob's anchors and edges only: all at once, then
  // refined in model order.
  std::vector<std::vector<Candidate>> quick(fitting_.size());
  quick_whole_.assign(fitting_.size(), 0);
  forEachModel(fitting_.size(), [&](size_t k) {
    bool whole = false;
    quick[k] = screen(*fitting_[k], Anchors::kQuick, &whole);
    quick_whole_[k] = whole;
  });
  std::vector<std::pair<double, size_t>> order;
  for (size_t k = 0; k < fitting_.size(); ++k) {
    order.emplace_back(quick[k].empty() ? -1.0 : quick[k].front().score, k);
    refine(quick[k]);
  }
  choose();
  // A part found beside one whole untaught copy of a type (its mirror
  // image, a larger copy): nothing else to look for. Beside one whole part
  // the quick search missed, that part is placed from its reading.
  if (!explainsWhole() && settleRest()) return matches();
  if (!explainsWhole()) fullSearch(std::move(order));
  if (changed_) choose();
  // A part the anchors did not lead to: under a front light at 30 grey
  // levels of contrast, or on a textured belt, the noisy outline's corners
  // open 20 to 70 degrees away from the model's (a star's 21 degree tip
  // fitted as a 90 degree corner), and no pose is proposed, though the part
  // at its true pose screens at 0.94 there. What the parts found leave is
  // then most often that part, less what they hide of it: its middle is
  // within a dozen pixels of the part's reference point, and the turn is
  // scanned about there (proposeAbout). Four unseen types, 40 scenes of 4
  // parts a condition, parts found of 160 at 30 levels of contrast, on a
  // textured belt and on wood: touching 154, 155, 157 before, 158, 160, 160
  // with it; overlapping 154, 152, 155 before, 160, 158, 159 with it (157,
  // 155, 156 searched at the middle alone); nothing falsely reported.
  if (!explainsWhole() && refinements_ < budget_ && !settleRest()) {
    searchRestMiddle();
    if (changed_) choose();
  }
  return matches();
}

std::vector<Match> BlobSearch::matches() const {
  std::vector<Match> found;
  // A part is touching when the blob holds more than it: other parts, or
  // pixels its placed outline leaves over. One part that covers the blob
  // but a rim of kAloneRimPx (a lone part the whole-region tests refused,
  // found here) touches nothing: its region is its own, however loosely
  // the model fits it.
  const bool alone = taken_.size() == 1 && coversBlob(kAloneRimPx);
  for (const size_t i : taken_) {
    const Candidate& c = *placed_[i].candidate;
    Match match;
    match.model = c.model;
    match.region = index_;
    match.score = c.score;
    match.centroid = c.pose.centre;
    match.symmetry_deg = c.model->symmetryDeg();
    match.angle_deg = reportedTurnDeg(*c.model, c.pose.angle_deg);
    match.from_edges = true;
    match.touching = !alone;
    found.push_back(match);
  }
  return found;
}

}  // namespace touching

std::vector<Match> locateInBlob(const std::vector<Region>& regions, size_t index,
                                const std::vector<const PartModel*>& models,
                                const EdgeDistance* built_edges, const LoneRegionTest* read_rest) {
  touching::BlobSearch search(regions, index, models, built_edges, read_rest);
  return search.run();
}

}  // namespace picksight::vision
