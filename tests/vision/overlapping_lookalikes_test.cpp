// Two look-alike public silhouettes (Kimia-99 hands, one 10 % larger than the
// other) lying on each other: a partly hidden hand is reported as its own
// type or not at all, never as the other hand, which verifies on it within
// the edge tolerance where the rest is hidden.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "picksight/synthetic/front_light.hpp"
#include "picksight/synthetic/silhouette_scene.hpp"
#include "silhouette_support.hpp"

using namespace picksight::vision;
using namespace picksight::test;
namespace ps = picksight::synthetic;

namespace {
// A report this close to a drawn part's centroid is about that part.
constexpr double kNearPx = 12;

// The hands the silhouette benchmark confused, at its sizes, and a part
// of another kind to lie on them.
const std::vector<SilhouetteSpec>& handSpecs() {
  static const std::vector<SilhouetteSpec> specs = {
      {"hand 7_1", "shapes/kimia99/trainimage7_1.png", 220},
      {"hand 7_4", "shapes/kimia99/trainimage7_4.png", 200},
      {"hand 6_4", "shapes/kimia99/trainimage6_4.png", 240},
  };
  return specs;
}

struct HandCount {
  int hidden_hands = 0;  // drawn with more than 5 % of their outline hidden
  int found = 0;         // reports, each checked
  int confused = 0;      // reports on no drawn part or on one of another type
};

// Overlapping scene `seed` of the hands drawn with `look`.
ps::SilhouetteScene handScene(const SilhouetteModels& models,
                              const ps::SilhouetteSceneOptions& look, uint64_t seed) {
  ps::SilhouetteSceneOptions o = look;
  o.arrangement = ps::Arrangement::kOverlapping;
  o.width = 1280;
  o.height = 720;
  o.parts = 10;
  o.seed = seed;
  o.distractor_share = 0;
  return ps::SilhouetteScene(models.types, models.chiral, o);
}

// Recognizes the overlapping scenes of `seeds` drawn with `look` and checks
// that every report is about a drawn part of its own type. Every confusion
// fails a check and is told, the scan goes on.
// `front`: under a front light (see trainSilhouettes).
HandCount checkHandsNeverConfused(const ps::SilhouetteSceneOptions& look,
                                  const std::vector<uint64_t>& seeds, bool front = false) {
  const auto& specs = handSpecs();
  const SilhouetteModels models = trainSilhouettes(specs, look, 7, front);
  HandCount count;
  for (const uint64_t seed : seeds) {
    const ps::SilhouetteScene scene = handScene(models, look, seed);
    for (const auto& t : scene.truth()) count.hidden_hands += t.type < 2 && t.hidden > 0.05 ? 1 : 0;
    for (const auto& m : recognizeSilhouettes(scene, 0, models, front)) {
      count.found += 1;
      // The drawn part nearest the report, to tell what it was taken for.
      const ps::SilhouettePart* nearest = nullptr;
      double distance = 1e9;
      for (const auto& t : scene.truth()) {
        const double d = std::hypot(t.centre.x - m.centroid.x, t.centre.y - m.centroid.y);
        if (d < distance) {
          distance = d;
          nearest = &t;
        }
      }
      const ps::SilhouettePart* near = drawnNear(scene.truth(), m, kNearPx);
      const bool right = near != nullptr && static_cast<size_t>(m.model->type) == near->type;
      count.confused += right ? 0 : 1;
      INFO("seed " << seed << ": " << m.model->name << " (score " << m.score << ") reported at "
                   << m.centroid.x << ", " << m.centroid.y << ", " << distance << " px from a "
                   << (nearest ? specs[nearest->type].name : std::string("nothing")) << " with "
                   << (nearest ? 100 * nearest->hidden : 0.0) << " % of its outline hidden");
      CHECK(right);
    }
  }
  return count;
}

std::vector<uint64_t> seedsUpTo(uint64_t last) {
  std::vector<uint64_t> seeds;
  for (uint64_t s = 1; s <= last; ++s) seeds.push_back(s);
  return seeds;
}

// As the benchmark's blurred look: a soft camera and a noisy sensor.
ps::SilhouetteSceneOptions blurred() {
  ps::SilhouetteSceneOptions look;
  look.blur_sigma = 1.5;
  look.noise_sigma = 8;
  return look;
}
}  // namespace

TEST_CASE("a partly hidden hand is never reported as the look-alike hand",
          "[vision][locator][overlap]") {
  // Of seeds 1 to 60: 1 to 12 and 26, where the hand 7_4 was reported as a
  // partly hidden part on a hidden 7_1, its outline crossing the background
  // where the hands differ; 30 and 59, where it verified above the verify
  // fraction there and so was never asked whether it is hidden.
  const HandCount count = checkHandsNeverConfused(
      ps::SilhouetteSceneOptions(), {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 26, 30, 59});
  // Otherwise the test would test nothing.
  CHECK(count.hidden_hands >= 6);
  CHECK(count.found >= 30);
}

TEST_CASE("a partly hidden hand is never reported as the look-alike hand when blurred",
          "[vision][locator][overlap]") {
  // Seeds 31 and 59 of 1 to 60 under the benchmark's blurred look, where
  // the 7_4 verified above the verify fraction on a hidden 7_1; 55, where
  // the 7_1 showed 0.69 of its boundary on a 7_4 12 % hidden, fitted at
  // 1.08 px (a partly hidden part that shows under 0.7 must fit closely).
  const HandCount count = checkHandsNeverConfused(blurred(), {31, 55, 59});
  CHECK(count.found >= 8);
}

// Not run by CTest: seeds 1 to 60 sharp and blurred, every confusion
// printed (`vision_overlap_test "[.][scan]"`), as scanned before changing
// the blob search.
TEST_CASE("look-alike hands scanned over 60 scenes sharp and blurred", "[.][scan]") {
  for (const auto& look : {ps::SilhouetteSceneOptions(), blurred()}) {
    const HandCount count = checkHandsNeverConfused(look, seedsUpTo(60));
    WARN("blur " << look.blur_sigma << ": " << count.found << " reports, " << count.confused
                 << " confused, " << count.hidden_hands << " hands more than 5 % hidden");
  }
}

// Not run by CTest: the same 60 scenes under a front light at 30 grey levels
// of contrast on a textured belt (the front-light benchmark's low
// contrast), where a thin stretch of a hand may not show at all.
TEST_CASE("look-alike hands scanned over 60 scenes at low contrast", "[.][scan]") {
  ps::SilhouetteSceneOptions look;
  REQUIRE(ps::frontLightCondition("low-contrast", &look.front, &look.part_level,
                                  &look.background_level));
  const HandCount count = checkHandsNeverConfused(look, seedsUpTo(60), true);
  WARN("low contrast: " << count.found << " reports, " << count.confused << " confused, "
                        << count.hidden_hands << " hands more than 5 % hidden");
}
