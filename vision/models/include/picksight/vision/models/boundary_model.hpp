// Boundary models: a region's contours (outer and holes) as straight lines and
// circular arcs within a conformity tolerance, the corners between them, the
// samples along them and distances to them in the model frame. Verifying a
// pose against an image's edges is boundary_verification.hpp's.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace picksight::vision {

enum class PrimitiveKind { kLine, kArc };

struct Primitive {
  PrimitiveKind kind = PrimitiveKind::kLine;
  cv::Point2d start;
  cv::Point2d end;
  // Arcs: centre, radius and the signed sweep from start to end (degrees,
  // positive from the image x axis towards the y axis; 360 for a full circle).
  cv::Point2d centre;
  double radius = 0;
  double sweep_deg = 0;
  double weight = 1;  // share of this edge in the verified fraction
  // Where the teach image's edge lay beyond the primitive (thousandths of
  // a pixel along its normal, away from the body), at
  // edgeOffsetCount(length()) points evenly spread along it (the k-th at
  // t = (k + 0.5) / count); empty: on it. Lines and arcs follow a part's
  // outline only within the conformity; a part's edges are fitted to them
  // plus these, so that where a stretch of a part is hidden (another part
  // lies on it) the rest does not pull the fit by the primitives' own
  // departures from the outline. Whole thousandths: the file holds them
  // exactly, and the edges' noise is tens of them.
  std::vector<int16_t> edge_offsets_mpx;
  // Where the teach image's edge was weaker along the primitive than its
  // weight says: the weight at each of edgeOffsetCount(length()) points
  // (placed as the edge offsets), in whole percent of `weight`; empty: the
  // whole weight throughout. A stretch of the surface as dark as the part
  // joined to it in the teach image (a stone of a gravel bed) is a few
  // pixels of a primitive whose other points lie on the part's own edge.
  // The boundary samples (verification, the blob search's tests) weigh by
  // it; the edge fit by `weight` alone (a stone's stretch still holds the
  // teach image's edge offsets: fitted without it, separated parts on
  // gravel turned 0.036 -> 0.044 degree RMS off).
  std::vector<uint8_t> edge_weights_pct;

  double length() const;
  // The primitive's weight at `t`: `weight` times the share held for the
  // point whose stretch of the primitive holds t (weightPctAt, 100 without
  // edge weights).
  double weightAt(double t) const { return weight * 0.01 * weightPctAt(t); }
  int weightPctAt(double t) const;
  // The teach image's edge offset at `t` (linear between the points; 0
  // without offsets).
  double edgeOffsetAt(double t) const;
  cv::Point2d pointAt(double t) const;  // t in [0, 1] from start to end
  cv::Point2d startDirection() const;   // unit tangent, in the walking direction
  cv::Point2d endDirection() const;
};

// The number of edge offsets a primitive of `length` px holds: one a pixel.
int edgeOffsetCount(double length);
// Edge offsets are within this of their primitive (px): the conformity
// the primitives were fitted within, and the blur, are less.
constexpr double kMaxEdgeOffsetPx = 3.0;
// An edge offset in px, as stored (Primitive::edge_offsets_mpx).
int16_t edgeOffsetMpx(double px);

struct BoundaryLoop {
  bool hole = false;
  double weight = 1;  // per-region weight (outer boundary, each hole)
  std::vector<Primitive> primitives;
};

struct Range {
  double min = 0;
  double max = 0;
  bool contains(double v) const { return v >= min && v <= max; }
};

enum class CornerClass { kLineLine, kLineArc, kArcLine, kArcArc };
const char* cornerClassName(CornerClass c);

// The meeting of two consecutive primitives of a loop, with the ranges a
// matching image corner may take (lengths may be shorter in the image, where
// another part hides an edge).
struct Corner {
  CornerClass kind = CornerClass::kLineLine;
  int loop = 0;
  int index = 0;  // of the outgoing primitive in its loop
  cv::Point2d at;
  double direction_in_deg = 0;  // tangent directions, image axes
  double direction_out_deg = 0;
  Range turn_deg;  // signed turn from incoming to outgoing tangent
  bool convex = true;
  Range length_in;
  Range length_out;
  Range radius_in;  // arcs only (0..0 for lines)
  Range radius_out;
};

// Splits a closed contour into lines and arcs: every contour point lies
// within `conformity` pixels of its primitive.
std::vector<Primitive> fitPrimitives(const std::vector<cv::Point2d>& closed, double conformity);

// Loops from contours (outer first), fitted with fitPrimitives.
std::vector<BoundaryLoop> fitLoops(const std::vector<std::vector<cv::Point2d>>& contours,
                                   double conformity);

std::vector<Corner> findCorners(const std::vector<BoundaryLoop>& loops, double conformity);

struct BoundarySample {
  cv::Point2d point;
  double weight = 0;  // loop weight * edge weight * length represented
};

// Points every `step` pixels along every primitive.
std::vector<BoundarySample> sampleBoundary(const std::vector<BoundaryLoop>& loops,
                                           double step = 1.0);

// Distance (pixels) from `p` to the nearest primitive of the loops: exact,
// for comparing a model with itself turned or mirrored.
double boundaryDistance(const std::vector<BoundaryLoop>& loops, cv::Point2d p);

// The same, for points asked in order along a boundary: `nearest` names the
// primitive nearest to the last point asked (loop, then primitive; start
// with {0, 0}), whose distance is read first, and is set to this point's.
// Only faster: the distance is the same to the bit.
struct PrimitiveIndex {
  size_t loop = 0;
  size_t primitive = 0;
};
double boundaryDistance(const std::vector<BoundaryLoop>& loops, cv::Point2d p,
                        PrimitiveIndex* nearest);

// Distance (pixels) from `p` to one primitive.
double primitiveDistance(const Primitive& prim, cv::Point2d p);

// The bilinear reading of a CV_32F image at (x, y), in its pixel
// coordinates; `outside` unless 0 <= x < last.x and 0 <= y < last.y
// (`last`: the image's last column and row), which is tested in doubles
// before any conversion to int (a pose from degenerate geometry can put a
// point at NaN or infinity) and leaves a pixel's right and lower neighbours
// in the image.
inline float bilinearAt(const cv::Mat& image, double x, double y, cv::Point2d last, float outside) {
  if (!(x >= 0 && y >= 0 && x < last.x && y < last.y)) return outside;
  const int x0 = static_cast<int>(x);
  const int y0 = static_cast<int>(y);
  const float fx = static_cast<float>(x - x0);
  const float fy = static_cast<float>(y - y0);
  const float* r0 = image.ptr<float>(y0) + x0;
  const float* r1 = image.ptr<float>(y0 + 1) + x0;
  return (1 - fy) * ((1 - fx) * r0[0] + fx * r0[1]) + fy * ((1 - fx) * r1[0] + fx * r1[1]);
}

// boundaryDistance on a grid, for asking it of many points: exact at the
// grid nodes up to `reach` pixels from the boundary (`reach` farther, and
// outside the grid), bilinear between nodes `cell` pixels apart. Built once
// per model; immutable, so any number of threads may read it.
class BoundaryDistanceMap {
 public:
  BoundaryDistanceMap() = default;
  BoundaryDistanceMap(const std::vector<BoundaryLoop>& loops, double reach, double cell = 0.5);
  // Bilinear between cells; the reach outside the map. Inline: the hand
  // test asks it for every boundary sample of every candidate.
  float at(cv::Point2d p) const {
    return bilinearAt(distance_, (p.x - origin_.x) * inv_cell_, (p.y - origin_.y) * inv_cell_,
                      last_, reach_);
  }
  bool empty() const { return distance_.empty(); }
  float reach() const { return reach_; }

 private:
  cv::Mat distance_;  // CV_32F
  cv::Point2d origin_;
  cv::Point2d last_;  // the last cell's column and row (cols - 1, rows - 1)
  double inv_cell_ = 2.0;
  float reach_ = 0;
};

}  // namespace picksight::vision
