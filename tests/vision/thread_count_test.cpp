// One frame's parts do not depend on how many threads found them. The
// vision pass splits its work over every core (binarization by rows, the
// region pass and the shadow cut by region, recognition by region); a
// robot told a different pose for the same frame on a bigger machine, or
// when the pool was busy, could not be trusted. Every figure a LOCATE
// reply or a WHY line rests on is compared to the last bit with the serial
// run, on touching and overlapping silhouettes, under front light with
// shadows, glints and low contrast.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>

#include "picksight/synthetic/front_light.hpp"
#include "picksight/synthetic/silhouette_scene.hpp"
#include "picksight/vision/recognition/recognition_pass.hpp"
#include "same_region.hpp"
#include "silhouette_support.hpp"

namespace ps = picksight::synthetic;
namespace pv = picksight::vision;
namespace pt = picksight::test;

namespace {
// What one pass over a frame gives, as the cell would read it.
struct PassResult {
  cv::Mat mask;
  std::vector<pv::Region> regions;
  std::vector<pv::Match> matches;
};

PassResult runPass(const cv::Mat& grey, const std::vector<pv::PartModel>& models, int threads) {
  cv::setNumThreads(threads);
  PassResult out;
  out.mask = pv::binarize(grey, pt::silhouetteBinarization());
  out.regions = pv::findRegions(out.mask, pv::regionOptionsFor({}, models), grey);
  out.matches = pv::recognizeParts(out.regions, models, -1).matches;
  return out;
}

// Bit for bit: == on doubles, on purpose.
void requireSame(const PassResult& serial, const PassResult& parallel) {
  REQUIRE(cv::countNonZero(serial.mask != parallel.mask) == 0);
  REQUIRE(serial.regions.size() == parallel.regions.size());
  for (size_t i = 0; i < serial.regions.size(); ++i) {
    CAPTURE(i);
    pt::checkSameRegion(serial.regions[i], parallel.regions[i]);
  }
  REQUIRE(serial.matches.size() == parallel.matches.size());
  for (size_t i = 0; i < serial.matches.size(); ++i) {
    const pv::Match& a = serial.matches[i];
    const pv::Match& b = parallel.matches[i];
    CAPTURE(i);
    CHECK(a.model == b.model);
    CHECK(a.region == b.region);
    CHECK(a.centroid.x == b.centroid.x);
    CHECK(a.centroid.y == b.centroid.y);
    CHECK(a.angle_deg == b.angle_deg);
    CHECK(a.score == b.score);
    CHECK(a.from_edges == b.from_edges);
    CHECK(a.touching == b.touching);
  }
}

// Restores OpenCV's own thread count when the test case ends.
struct ThreadCountGuard {
  int before = cv::getNumThreads();
  ~ThreadCountGuard() { cv::setNumThreads(before); }
};
}  // namespace

TEST_CASE("a frame's parts are the same to the last bit whatever the number of threads",
          "[vision][threads]") {
  const ThreadCountGuard guard;
  // Curved, thin and own shapes, of the silhouette benchmark's sets.
  const std::vector<pt::SilhouetteSpec> specs = {
      {"frog", "shapes/tari1000/obj20_1.png", 180},
      {"spoon", "shapes/tari1000/obj29_1.png", 200},
      {"bone", "shapes/kimia99/trainimage9_1.png", 190},
      {"l_shape", "", 150},
      {"gear", "", 140},
  };
  struct Case {
    const char* light;
    ps::Arrangement arrangement;
  };
  const Case cases[] = {
      {"clean", ps::Arrangement::kTouching},        {"clean", ps::Arrangement::kOverlapping},
      {"shadow", ps::Arrangement::kTouching},       {"glossy", ps::Arrangement::kSeparated},
      {"low-contrast", ps::Arrangement::kTouching},
  };
  // Taught under even light (the parts alone: one region each, whatever
  // the light of the scenes).
  const pt::SilhouetteModels trained = pt::trainSilhouettes(specs, {});
  for (const Case& c : cases) {
    CAPTURE(c.light, static_cast<int>(c.arrangement));
    ps::SilhouetteSceneOptions look;
    REQUIRE(
        ps::frontLightCondition(c.light, &look.front, &look.part_level, &look.background_level));
    const ps::SilhouetteScene scene(trained.types, trained.chiral,
                                    pt::smallScene(look, 31, 10, 0.2, c.arrangement));
    const cv::Mat grey = scene.render(0);
    const PassResult serial = runPass(grey, trained.models, 1);
    // The frame holds parts the pass finds, so the comparison is of
    // something: most of the ten drawn.
    CHECK(serial.matches.size() >= 5);
    for (const int threads : {2, 3, 8}) {
      CAPTURE(threads);
      requireSame(serial, runPass(grey, trained.models, threads));
    }
  }
}
