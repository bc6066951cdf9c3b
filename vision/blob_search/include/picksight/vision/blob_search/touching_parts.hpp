// Parts inside merged blobs (parts that touch): pose hypotheses from the
// boundary model's corners and arcs, verification on the blob's edges,
// sub-pixel refinement on the grey-level edges, best-first acceptance.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "picksight/vision/models/boundary_verification.hpp"
#include "picksight/vision/models/match.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/segmentation/regions.hpp"

namespace picksight::vision {

// The model's side of the search for touching parts, derived by
// prepareModel (see PartModel::blob_search): built once per model, then
// read by any number of threads.
std::shared_ptr<const BlobSearchModel> makeBlobSearchModel(const PartModel& model);

struct EdgeFit {
  bool ok = false;
  ImagePose pose;
  double rms_px = 0;           // of the inlier edge points about the fitted boundary
  double inlier_fraction = 0;  // of the model's edge samples (weighted) found on an edge
  // The weighted boundary length (pixels) whose edge lies within a pixel of
  // the fitted boundary: how much of the region's edges the pose explains.
  double precise_length = 0;
};

// Moves `start` so that the model boundary lies on the region's grey-level
// edges (the 0.5 crossing of the region's coverage along each boundary
// normal): iterative least squares in (x, y, angle) plus a uniform offset
// of the boundary, which absorbs the half-pixel by which a boundary fitted
// to pixel centres lies inside the true edge. Edge points with no clean
// crossing (where the part touches another) are left out. `search_px`: how
// far along the normals an edge is looked for in the first iteration.
// `worth_finishing`, when given, is asked once with the pose the coarse
// passes settled on, before the dense passes that cost most of the fit:
// false ends the fit there (not ok), for a pose that can no longer matter.
EdgeFit refinePoseOnEdges(const PartModel& model, const Region& region, const ImagePose& start,
                          double search_px = 4.0, int iterations = 6,
                          const std::function<bool(const ImagePose&)>& worth_finishing = {});

// The centroid of the area the region's grey-level edges enclose (image
// coordinates), read along the normals of the model's boundary placed at
// `pose`, within `search_px` of it; where no clean crossing is (a contact,
// a corner, a notch deeper than the search, noise at low contrast), the
// edge runs between the crossings either side (the boundary moved by
// theirs, interpolated along it), not along the model's boundary, which
// cuts a furred outline's wiggles short by up to the conformity and left
// that out of every reading alike. On the front-light benchmark at 30 grey
// levels 3.5 % of the samples found no crossing; taught with the boundary
// there, parts separated were placed 0.068 px off (one type 0.14 px, with
// 7 teach views still 0.11), with the crossings either side 0.055 (4
// scenes; touching 0.071 -> 0.062, on wood 0.054 / 0.048 -> 0.048 / 0.042).
// None for a model of no area.
std::optional<cv::Point2d> outlineCentroid(const PartModel& model, const Region& region,
                                           const ImagePose& pose, double search_px = 1.5);

// Moves each primitive of `loops` (model frame: image point minus `origin`)
// onto the grey-level edges of `region`, the part it was fitted to: lines by
// a shift and a turn, arcs by a new circle, each a least-squares fit to the
// edge crossings along its normals. Pixel-centre contours lie 0.3 to 0.5 px
// inside the true edge, by an amount that changes with an edge's slope, so
// a model left there is off-centre by tenths of a pixel wherever parts
// are located from their edges.
void snapToEdges(std::vector<BoundaryLoop>& loops, const Region& region, cv::Point2d origin);

// Sets each primitive's edge offsets (Primitive::edge_offsets_mpx) to where the
// grey-level edges of `region` cross its normals (model frame as in
// snapToEdges), bridged where none crosses cleanly.
// A part with rotational symmetry of order `turns` is found at any of its
// turns: each offset is then the mean of the crossings read with the model
// turned by each of them about the origin.
void measureEdgeOffsets(std::vector<BoundaryLoop>& loops, const Region& region, cv::Point2d origin,
                        int turns = 1);

// The parts of the given models inside region `index` of `regions`, a blob
// that matched no model as a whole. Best score first; Match::touching set
// unless one part explains the blob whole.
// A part whose mirrored model verifies about as well is not reported. Of two
// poses that cannot both be parts (they would share more than parts lying
// on each other do), the one lying on more of the blob's edges is reported.
// `edges`: the blob's edge map if its region tests built one (see
// RegionCache::edges; reaching twice the largest edge tolerance of
// `models`, past the region's box by more), which the search then reads
// instead of building its own: the same distances as far as anything here
// reads them.
// `read_rest`, when given: what a region is, read as the region tests read
// a lone region (see readLoneRegion). What the parts found leave of the
// blob, when it is one piece that this reads as one whole copy of a taught
// type that no model takes for a part (its mirror image, or a larger copy),
// is not searched further: no part lies there (it is the blob's untaught
// object, touching the parts found). Where it reads as one part, that part
// is placed from the reading's pose before any search.
struct LoneReading {
  enum class Kind { kNeither, kPart, kCopy };
  Kind kind = Kind::kNeither;
  // kPart: the model that passes it (the first in rank among those that
  // do) and its turn there, about the region's centroid (unrefined).
  const PartModel* model = nullptr;
  double angle_deg = 0;
};
using LoneRegionTest = std::function<LoneReading(const Region&)>;
std::vector<Match> locateInBlob(const std::vector<Region>& regions, size_t index,
                                const std::vector<const PartModel*>& models,
                                const EdgeDistance* edges = nullptr,
                                const LoneRegionTest* read_rest = nullptr);

}  // namespace picksight::vision
