// Why a region is not a part of a model: the first of recognize()'s tests
// it fails for the model it comes nearest to, with the measured value and
// the tolerance, for the results stream and the robot's WHY.
//
// Pure functions on the same regions and models recognize() sees (frame
// pixels); the thresholds are the models' own (area_tolerance,
// hu_tolerance, verify_percent, edge_tolerance), so an explanation never
// disagrees with the recognizer about a separated region.
#pragma once

#include <string>
#include <vector>

#include "picksight/vision/part_model.hpp"
#include "picksight/vision/regions.hpp"

namespace picksight::vision {

// The tests in recognize()'s order; kPasses: the region passes every test
// of that model (it is that part, or a touching blob searched further).
enum class RegionTest { kEdge, kHoles, kArea, kHu, kMirror, kVerify, kPasses };

// "edge", "holes", "area", "hu", "mirror", "verify", "passes".
const char* regionTestName(RegionTest test);

struct RegionExplanation {
  const PartModel* nearest = nullptr;  // borrowed from the list; null: no models
  RegionTest test = RegionTest::kPasses;
  // The value measured and its tolerance (low == high for a single bound):
  // area in pixels, holes as counts, Hu distance (also for a mirror image
  // found by its moments: the distance, which the mirrored invariants would
  // pass), verify as percent of the boundary, a mirror image found on the
  // boundary as the mirror's verified percent against the model's.
  double measured = 0;
  double low = 0;
  double high = 0;
};

// The model of `models` the region comes nearest to (the one whose tests it
// passes furthest, then the closest in area) and the first test it fails.
RegionExplanation explainRegion(const Region& region, const std::vector<const PartModel*>& models);

}  // namespace picksight::vision
