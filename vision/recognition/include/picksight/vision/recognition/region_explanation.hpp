// Why a region is not a part of a model: the first of recognize()'s tests
// it fails for the model it comes nearest to, with the measured value and
// the tolerance, for the results stream and the robot's WHY.
//
// Pure functions on the same regions and models recognize() sees (frame
// pixels); the verdicts are judgeRegion's, the recognizer's own, so an
// explanation never disagrees with the recognizer about a separated region.
#pragma once

#include <optional>
#include <vector>

#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/recognition/region_judge.hpp"
#include "picksight/vision/segmentation/regions.hpp"

namespace picksight::vision {

struct RegionExplanation {
  const PartModel* nearest = nullptr;  // borrowed from the list; null: no models
  // The first test the region fails for `nearest` (kEdge: the frame border
  // cuts it, which findRegions leaves out of recognition); kPasses: it
  // passes every test of that model (it is that part, or a touching blob
  // searched further).
  RegionTest test = RegionTest::kPasses;
  // The value measured and its tolerance, as in Verdict.
  double measured = 0;
  double low = 0;
  double high = 0;
  // explainRegionAsAsked: the region passes every test of `nearest`, a
  // model of another type than the one asked.
  bool other_type = false;
};

// The model of `models` the region comes nearest to (the one whose tests it
// passes furthest; among those passing every test the best verified, as
// recognize() picks; else the closest in area) and the first test it
// fails. `region` is as findRegions found it with the smallest minimum hole
// area of the models: each model judges it with its own min_hole_area.
RegionExplanation explainRegion(const Region& region, const std::vector<const PartModel*>& models);

// Why `LOCATE <asked_type>` left the region out (-1: every type, as
// explainRegion): a region that passes every test of another type's model
// (the nearest of all `models`) is that type's part (`other_type`);
// otherwise the nearest of the asked type's models and the first test it
// fails.
RegionExplanation explainRegionAsAsked(const Region& region,
                                       const std::vector<const PartModel*>& models, int asked_type);

// How far off a model a region must lie to be plainly unlike that part, in
// that model's own tolerances. A tolerance is what its integrator said a
// real part varies by (lens, height, piece to piece, light); a region off
// by twice that is no such part measured a little off, and nobody would
// double a tolerance for it. One closer (a part a little beyond its
// tolerance, one a shadow joined) stays a near miss worth a look.
constexpr double kUnlikeTolerances = 2;
// The tolerances "far" is measured from at the least: those LEARN sets
// (its default area tolerance, its smallest Hu tolerance). A tolerance
// tightened below them says the parts vary less, not that a region just
// past it is unlike the part: the near misses a tightened tolerance
// refuses keep their sentence.
constexpr double kUnlikeMinAreaTolerance = 0.1;
constexpr double kUnlikeMinHuTolerance = 0.5;
// A region of a model's shape (within kUnlikeTolerances of its Hu
// tolerance), with the model's holes and at most one more, is never unlike
// it while its area lies within these multiples of the model's: the part's
// shape at another size is a size confusion worth a look (the front-light
// benchmark's copies are 0.8 and 1.25 times a part's size), however far
// its area is from the tolerance, and a speckle's hole in such a copy must
// not hide it (refused for its holes first, a 0.8 copy read unlike the
// part by its area alone in clang's build).
constexpr double kUnlikeMinCopyArea = 0.5;
constexpr double kUnlikeMaxCopyArea = 2.0;

// Whether `region` is plainly unlike every one of `models` (false with
// none): for each model, its shape (the Hu distance) lies further than
// kUnlikeTolerances times its hu_tolerance, or its area further from the
// model's than kUnlikeTolerances times the model's area tolerance and
// outside kUnlikeMinCopyArea..kUnlikeMaxCopyArea of it (each tolerance at
// least kUnlikeMinAreaTolerance, kUnlikeMinHuTolerance). A region
// the frame's border cuts is no whole part's shape, and the frame may hide
// any share of its area and holes: it is unlike a model only when too
// large by that margin or with more holes than the part (as the model
// counts them). Frame pixels, as recognize().
bool unlikeEveryModel(const Region& region, const std::vector<const PartModel*>& models);

// One tolerance of one model changed (`TOLERANCE <type> <key> <value>`).
struct RegionRemedy {
  int type = -1;
  // "area_tolerance", "hu_tolerance", "verify_percent" or "mirror_symmetric"
  // (the keys of TOLERANCE and of the model file).
  const char* key = "";
  double value = 0;  // as written with `decimals` decimals
  int decimals = 0;
};

// The smallest change of the tolerance `why` names (area or scale: the area
// tolerance; Hu distance, verification, mirror) on its nearest model with which `LOCATE
// <asked_type>` accepts the region, with a margin for the next frame (a
// Hu distance or area gap 10 % past the measured one, a verified share 2
// points below it), or none: a region another test would still refuse,
// or one no tolerance within its bounds admits. Checked, not
// estimated: the changed models are run through recognizeParts() on the
// region, so a remedy named is one LOCATE takes. `why` is
// explainRegionAsAsked's on `region` with pointers into `models` (frame
// pixels, as LOCATE judged it).
std::optional<RegionRemedy> remedyFor(const Region& region, const std::vector<PartModel>& models,
                                      const RegionExplanation& why, int asked_type);

}  // namespace picksight::vision
