// Public silhouettes (Tari-1000) and the repository's L shape among their own
// mirror images and 0.8x / 1.25x copies: only the parts as trained are
// reported, each where it was drawn, also when blur and noise close a hole.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "picksight/synthetic/silhouette_scene.hpp"
#include "silhouette_support.hpp"

using namespace picksight::vision;
using namespace picksight::test;
namespace ps = picksight::synthetic;

namespace {
// A report this close to a drawn part's centroid is about that part; parts
// lie gap_px (8) apart, so no report is near two.
constexpr double kNearPx = 12;
}  // namespace

TEST_CASE("mirrored and rescaled public silhouettes are never reported", "[vision][mirror]") {
  const ps::SilhouetteSceneOptions look;
  // Chiral shapes (so that mirrored copies are drawn), curved and polygonal;
  // the turtle and the L shape are those a layout once made go missing.
  const std::vector<SilhouetteSpec> specs = {
      {"turtle", "shapes/tari1000/obj4_1.png", 170},
      {"bottle", "shapes/tari1000/obj32_1.png", 190},
      {"frog", "shapes/tari1000/obj20_1.png", 180},
      {"l_shape", "", 160},
  };
  const SilhouetteModels models = trainSilhouettes(specs, look);
  // Every type here is chiral: each gets mirrored distractors too.
  for (size_t i = 0; i < specs.size(); ++i) {
    INFO(specs[i].name);
    CHECK(models.chiral[i]);
  }

  int distractors = 0;
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    const ps::SilhouetteScene scene(models.types, models.chiral, smallScene(look, seed, 12, 0.5));
    std::vector<int> found(scene.truth().size(), 0);
    for (const auto& m : recognizeSilhouettes(scene, 0, models)) {
      INFO("seed " << seed);
      const ps::SilhouettePart& near = drawnUnder(scene.truth(), m, kNearPx);
      INFO(m.model->name << " reported on " << specs[near.type].name << " kind "
                         << static_cast<int>(near.kind) << " at " << near.centre.x << ", "
                         << near.centre.y);
      CHECK(near.kind == ps::PartKind::kTrue);
      CHECK(static_cast<size_t>(m.model->type) == near.type);
      found[static_cast<size_t>(&near - scene.truth().data())] += 1;
    }
    for (size_t i = 0; i < scene.truth().size(); ++i) {
      const auto& t = scene.truth()[i];
      if (t.kind != ps::PartKind::kTrue) {
        ++distractors;
        continue;
      }
      INFO("seed " << seed << ": " << specs[t.type].name << " at " << t.centre.x << ", "
                   << t.centre.y << " turned " << t.angle_deg);
      CHECK(found[i] == 1);
    }
  }
  // Otherwise the test would test nothing.
  CHECK(distractors >= 6);
}

TEST_CASE("a blurred noisy mirror image of a chiral blob is not reported",
          "[vision][mirror][locator]") {
  // Defocused and noisy, the training image the benchmark renders for this
  // chiral blob (seed 16) shows a pinhole of noise in it, which was once
  // taught as the part's hole: the copies where it did not show then failed
  // the hole test and were searched for parts from their edges, where the
  // mirror image had to be told from the part. A pinhole is no hole now
  // (regions.cpp, kMaxPinholePx): every copy is judged whole, and its
  // mirror image must still be told from the part.
  ps::SilhouetteSceneOptions look;
  look.blur_sigma = 1.5;
  look.noise_sigma = 8;
  const SilhouetteModels models =
      trainSilhouettes({{"blob", "shapes/tari1000/obj7_1.png", 180}}, look, 16);
  REQUIRE(models.models[0].body.holes == 0);
  REQUIRE(models.chiral[0]);

  int mirrored = 0;
  int found = 0;
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    const ps::SilhouetteScene scene(models.types, models.chiral, smallScene(look, seed, 12, 0.7));
    for (uint64_t frame = 0; frame < 2; ++frame) {
      for (const auto& m : recognizeSilhouettes(scene, frame, models)) {
        INFO("seed " << seed << " frame " << frame);
        const ps::SilhouettePart& near = drawnUnder(scene.truth(), m, kNearPx);
        INFO("reported at " << m.centroid.x << ", " << m.centroid.y
                            << (m.from_edges ? " from its edges" : " as a whole region"));
        const bool as_trained = near.kind == ps::PartKind::kTrue;
        CHECK(as_trained);
        found += as_trained ? 1 : 0;
      }
      for (const auto& t : scene.truth()) mirrored += t.kind == ps::PartKind::kMirrored ? 1 : 0;
    }
  }
  // Otherwise the test would test nothing.
  CHECK(mirrored >= 12);
  CHECK(found >= 6);
}
