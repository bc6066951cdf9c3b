// The recognizer's tests of one region against one model, in one place:
// recognize() picks its match from these verdicts and explainRegion() names
// the first test failed from the same ones, so the two cannot disagree.
//
// Threading: a RegionCache belongs to one thread (it fills itself on first
// use); models and regions are only read.
#pragma once

#include <map>
#include <memory>
#include <vector>

#include "picksight/vision/models/boundary_model.hpp"
#include "picksight/vision/models/boundary_verification.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/segmentation/blob_features.hpp"
#include "picksight/vision/segmentation/regions.hpp"

namespace picksight::vision {

// The tests in the order a region gets further with a model: a region
// failing a later one resembles the model more. kScale and kMirror: the
// region is the whole part drawn other than trained (a scaled copy, its
// mirror image); kPasses: it passes every test (it is that part).
enum class RegionTest { kEdge, kHoles, kArea, kHu, kVerify, kScale, kMirror, kPasses };

// "edge", "holes", "area", "hu", "verify", "scale", "mirror", "passes".
const char* regionTestName(RegionTest test);

// The holes of `region` at least `min_hole_area` large (pixels, inside
// their boundary trace, as findRegions measures them).
int holesAtLeast(const Region& region, double min_hole_area);

// Whether any of `regions` has a hole smaller than `min_hole_area`.
bool hasHoleBelow(const std::vector<Region>& regions, double min_hole_area);

// The region as a model trained with `min_hole_area` sees it: smaller holes
// and their boundaries left out (moments and area unchanged).
Region withHolesAtLeast(const Region& region, double min_hole_area);
// The same for every region: same order, so indices hold.
std::vector<Region> withHolesAtLeast(const std::vector<Region>& regions, double min_hole_area);

// What the tests read of one region, computed on first use and shared by
// every model judged on it: the log Hu invariants, the edges' distance map
// and the phases of its complex moments. Keeps a reference to the region.
class RegionCache {
 public:
  // `max_edge_tolerance`: the largest edge tolerance of the models to be
  // judged; the distance map reaches twice that (all any test reads).
  RegionCache(const Region& region, double max_edge_tolerance);

  const Region& region() const { return region_; }
  const HuArray& logHu();
  const EdgeDistance& edges();
  // The edge map if edges() has built it, else null.
  const EdgeDistance* builtEdges() const { return edges_.get(); }
  // Phase of the complex moment of order k, degrees (0 for k <= 0).
  double phaseDeg(int k);

 private:
  const Region& region_;
  double max_edge_tolerance_;
  bool hu_ready_ = false;
  HuArray log_hu_{};
  std::unique_ptr<EdgeDistance> edges_;
  std::map<int, double> phase_deg_;  // by orientation order
};

// One model's verdict on a region.
struct Verdict {
  RegionTest test = RegionTest::kPasses;
  // The value measured and its bounds (low == high for a single bound):
  // holes as counts; area in pixels; hu: the Hu distance; verify: percent
  // of the boundary verified; scale: the copy's scale against 1 +- the
  // scale the area tolerance allows; mirror: the mirror image's verified
  // percent against the model's; passes: the verified percent against
  // verify_percent.
  double measured = 0;
  double low = 0;
  double high = 0;
  // Set once the region passes the Hu test: the Hu distance; once it
  // reaches verification: the verified fraction (0..1) and the rotation
  // reported for the model's best pose (degrees, not wrapped).
  double hu_distance = 0;
  double score = -1;
  double angle_deg = 0;
};

// The body tests of judgeRegion, in its order: holes (`holes`: the region's
// count as the model sees them, see holesAtLeast), area, Hu distance. The
// first failed, with its measured value and bounds, or kPasses with
// hu_distance set (score unset). Without judgeRegion's scaled-copy search:
// the gates recognize(), explainRegion() and the cell's `LOCATE <type>`
// screen across types all apply.
Verdict judgeBody(RegionCache& cache, const PartModel& model, int holes);

// Of two verdicts that pass every test, whether `a` ranks above `b`: it
// verifies on more of the boundary (by more than 1e-9), or as much and
// nearer on the Hu distance. The one ranking of passing models:
// recognize() reports the first, explainRegion() names it.
bool ranksAbove(const Verdict& a, const Verdict& b);

// The models by their minimum hole area, smallest first: each group judges
// a region with its smaller holes left out (withHolesAtLeast), as it was
// trained to see it. The one grouping of recognizeEachHoleSetting() and
// explainRegion().
std::map<double, std::vector<const PartModel*>> byMinHoleArea(
    const std::vector<const PartModel*>& models);

// The tests of recognize(), in its order, on the region as the model sees
// it (its holes counted as the caller found them; see withHolesAtLeast):
// holes, area (a region outside the area tolerance whose body and boundary
// fit a copy of the model scaled 0.6x..1.6x, either hand, is kScale),
// Hu distance, verification at the refined best rotation candidate, and
// for a chiral model whether the mirror image fits better. `check_scale`
// false skips the scaled-copy search (the area verdict stands): for a
// caller that already knows the region is a whole part.
Verdict judgeRegion(RegionCache& cache, const PartModel& model, bool check_scale = true);

}  // namespace picksight::vision
