// What the touching-parts files share: boundary anchors (corners, arcs), the
// model's search data, screened candidates and the coverage reader. Not
// installed: only touching_parts*.cpp include it.
#pragma once

#include <cmath>
#include <memory>
#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/common/angles.hpp"
#include "picksight/vision/models/boundary_model.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/segmentation/blob_features.hpp"
#include "picksight/vision/segmentation/regions.hpp"

namespace picksight::vision {
namespace touching {

using picksight::kRadPerDeg;

inline double angleOf(cv::Point2d v) { return std::atan2(v.y, v.x) / kRadPerDeg; }

inline cv::Point2d rotate(cv::Point2d p, double c, double s) {
  return {c * p.x - s * p.y, s * p.x + c * p.y};
}

// Twice the signed area of a loop: > 0 when its interior lies on the side of
// the left normal (-t.y, t.x) of the walking direction t.
double loopOrientation(const BoundaryLoop& loop);

// Offsets along a closed loop's normals, one a sample: each sample's edge
// crossing where it has one, and where it has none, the crossings of the
// nearest samples either side that have, weighed by how near each lies
// round the loop (a straight run between them). All 0 when no sample has
// one. A gap in the crossings (a corner, a notch deeper than the search, a
// stretch of noise at low contrast) is read as the edge it lies on, not as
// the model's boundary, which deviates from a rough outline by up to the
// conformity.
std::vector<double> bridgedOffsets(const std::vector<std::optional<double>>& crossings);

// A corner as an unordered pair of edges leaving a point, so that it reads
// the same on a mirrored model: the bisector of the two edges, the opening
// angle between them, and whether the body fills the opening.
struct CornerAnchor {
  cv::Point2d at;
  double bisector_deg = 0;
  cv::Point2d bisector;  // the unit vector: turns between corners without a sine
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

// The corners and arcs of fitted loops (model frame or image).
void anchorsOf(const std::vector<BoundaryLoop>& loops, std::vector<CornerAnchor>* corners,
               std::vector<ArcAnchor>* arcs);

// A boundary point of the model with its normal pointing away from the body.
struct EdgeSample {
  cv::Point2d point;
  cv::Point2d normal;
  double weight = 0;
  double offset = 0;  // the teach image's edge beyond it (Primitive::edge_offsets_mpx)
};

// The model's edge samples every `step` pixels, away from primitive ends.
std::vector<EdgeSample> edgeSamples(const PartModel& model, double step);

// Bilinear reading of a region's coverage (0 outside its box).
class Coverage {
 public:
  explicit Coverage(const Region& r)
      : c_(r.coverage), origin_(r.coverage_origin), last_(c_.cols - 1, c_.rows - 1) {}
  float at(cv::Point2d p) const {
    return bilinearAt(c_, p.x - origin_.x, p.y - origin_.y, last_, 0.f);
  }

 private:
  const cv::Mat& c_;
  cv::Point origin_;
  cv::Point2d last_;  // the last column and row
};

// Where the grey image shows a part the mask lost: pixels joined to a blob
// darker than the surface round it by kFaintShare of the contrast between
// the blob's level and the surface's (lighter, for light parts: the
// contrast's sign follows). At low contrast the threshold drops the thin
// limbs of a part whose light is uneven (a shaded side 15 levels lighter on
// a contrast of 30); its boundary there is not on the background. Empty
// (nothing faint) without a grey image or a contrast to read.
class FaintPart {
 public:
  // `blob`: 255 on the blob's pixels, over `blob_box` (image coordinates).
  FaintPart(const Region& r, const cv::Mat& blob, cv::Rect blob_box);
  bool at(cv::Point2d p) const;
  // How many of the pixels `drawn` (255 on them, over `box`, image
  // coordinates) covers are faint.
  int countIn(const cv::Mat& drawn, cv::Rect box) const;

 private:
  cv::Mat faint_;  // 255 where faint, over the region's grey box
  cv::Point origin_;
};

struct Candidate {
  const PartModel* model = nullptr;
  ImagePose pose;
  double score = 0;
  double rms = 0;
  double precise = 0;  // EdgeFit::precise_length, once refined
};

// A corner's first look counts boundary samples within this many edge
// tolerances: the blob's distance map must reach that far.
constexpr double kLooseScreenFactor = 2.0;
// proposeAbout's first look reads its map this much more loosely than the
// loose screening tolerance, so a map it reads reaches that much further.
constexpr double kAboutWidePx = 4.0;
// proposeAbout's reference points at last lie on a grid this far apart
// (pixels): a part whose reference point lies within it of a point searched
// about is found there.
constexpr double kAboutStepPx = 4.0;

}  // namespace touching

struct BlobSearchModel {
  std::vector<touching::CornerAnchor> corners;  // the most telling (keepTelling)
  std::vector<touching::ArcAnchor> arcs;        // likewise
  // The few most telling corners and arcs (indices into the above), which
  // a first, quick search of a blob starts from.
  std::vector<size_t> quick_corners;
  std::vector<size_t> quick_arcs;
  std::vector<BoundarySample> sparse;  // hypotheses are screened on these
  std::vector<BoundarySample> glance;  // after a first look at these
  // The glance samples farthest first from each corner (by index in
  // `corners`) and each arc's centre (`arcs`): a pose put on a wrong anchor
  // matches near it and fails far from it, so the first look ends sooner.
  std::vector<std::vector<BoundarySample>> corner_glance;
  std::vector<std::vector<BoundarySample>> arc_glance;
  std::vector<touching::EdgeSample> edges;  // poses are refined on these, 1 px apart
  double glance_weight = 0;                 // the glance samples' total
  double sparse_weight = 0;                 // the sparse samples' total
  Extent extent;                            // of the boundary samples (fitsIn)
  // The middle of the part's deepest core (touching::deepestCore of the
  // part drawn whole), model frame: where a blob's deepest core lies from
  // the part's reference point when the part holds it; and its depth
  // (pixels from the outline).
  cv::Point2d core_middle;
  double core_depth_px = 0;
};

namespace touching {

// The model's side of the search: derived by prepareModel, or built here
// for a model put together without it.
std::shared_ptr<const BlobSearchModel> searchOf(const PartModel& m);

// The corners of a blob the search starts from, with their indices in
// order of opening angle (each model corner visits only those it may be).
struct BlobCorners {
  explicit BlobCorners(std::vector<CornerAnchor> corners);
  std::vector<CornerAnchor> corners;
  std::vector<size_t> by_opening;
};

// Which of a model's corners and arcs a screening starts from: its quick
// ones (its sharpest corners and longest arcs, the first look at a corner
// forgiving a few degrees), all of them, or all but the quick ones (those
// a quick screening that kept every pose it found has searched already).
enum class Anchors { kQuick, kAll, kBeyondQuick };

// Screens the poses proposed for one model (its own hand; the mirror image
// is asked of each part about to be taken, in touching_parts.cpp) in a
// blob from the model's `anchors`: appends those that verify well enough on
// `edges` to `out`.
void propose(const PartModel& model, const BlobSearchModel& search, Anchors anchors,
             const BlobCorners& image_corners, const std::vector<ArcAnchor>& image_arcs,
             const EdgeDistance& edges, std::vector<Candidate>* out);

// The pose of `model` with its reference point at or within a dozen pixels
// of `centre` (image coordinates) that screens best, over the whole turn:
// a first look on `wide` (a map of the same outline reaching kAboutWidePx
// further than `edges`) at poses twice as far apart as the second, which
// reads `edges` about the first look's best; appended to `out` when it
// screens as well as propose() asks. For a part whose corners and arcs the
// blob's outline does not show as the model's.
// `from_core`: `centre` is where the part's deepest core lies, and its
// reference point is looked for about centre less the model's core_middle
// turned with the part, at every turn.
void proposeAbout(const PartModel& model, const BlobSearchModel& search, cv::Point2d centre,
                  const EdgeDistance& edges, const EdgeDistance& wide, std::vector<Candidate>* out,
                  bool from_core = false);

// The model's loops placed at a pose, as polygons in image coordinates:
// filled together, the holes stay empty.
std::vector<std::vector<cv::Point>> placedOutline(const PartModel& m, const ImagePose& pose);

// `m` drawn at `pose` (255 on it) over `*box`, its outline's box widened by
// `margin` pixels all round (image coordinates).
cv::Mat drawnPart(const PartModel& m, const ImagePose& pose, int margin, cv::Rect* box);

// The deepest core of `piece` (a mask over an image, 255 on the piece, `box`
// its bounding box): of its pixels deeper inside than half the deepest,
// those 8-connected to the deepest. Read at a reduced scale, as the rest's
// pieces are parted at their necks (`step_px`: a reduced pixel's side).
// None for an empty piece.
struct DeepestCore {
  cv::Point2d middle;  // image coordinates
  double depth_px;     // the deepest pixel's distance from the outline
  double step_px;
};
std::optional<DeepestCore> deepestCore(const cv::Mat& piece, const cv::Rect& box);

}  // namespace touching
}  // namespace picksight::vision
