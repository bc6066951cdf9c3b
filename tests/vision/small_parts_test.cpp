// Public silhouettes drawn small (90 and 120 px long, below the range the
// recognizer was tuned on) touching each other in merged blobs: every part
// that shows is found where it was drawn, and nothing else is reported; and
// the models of such outlines lie on the parts they were trained from.
#include <catch2/catch.hpp>

#include <algorithm>
#include <string>
#include <vector>

#include "picksight/codecs/codecs.hpp"

#include "picksight/synthetic/silhouette_scene.hpp"
#include "silhouette_support.hpp"

using namespace picksight::vision;
using namespace picksight::test;
namespace ps = picksight::synthetic;

namespace {
// A report this close to a drawn part's centroid is about that part.
constexpr double kNearPx = 8;
}  // namespace

TEST_CASE("small parts touching others are found however narrow their notches",
          "[vision][locator]") {
  const ps::SilhouetteSceneOptions look;
  const std::vector<SilhouetteSpec> specs = {
      // Spikes of 10 degrees: their tips show longer or shorter from one
      // drawing to the next at this size.
      {"spikes", "shapes/tari1000/obj6_1.png", 120},
      {"obj9", "shapes/tari1000/obj9_1.png", 90},
      {"obj18", "shapes/tari1000/obj18_1.png", 90},
      {"obj1", "shapes/tari1000/obj1_1.png", 90},
  };
  const SilhouetteModels models = trainSilhouettes(specs, look);

  int touching_found = 0;
  int parts = 0;
  int missed = 0;
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    const ps::SilhouetteScene scene(models.types, models.chiral,
                                    smallScene(look, seed, 12, 0, ps::Arrangement::kTouching));
    const auto matches = recognizeSilhouettes(scene, 0, models);
    for (const auto& m : matches) {
      INFO("seed " << seed);
      const ps::SilhouettePart& near = drawnUnder(scene.truth(), m, kNearPx);
      CHECK(static_cast<size_t>(m.model->type) == near.type);
    }
    for (const auto& t : scene.truth()) {
      const auto found = std::find_if(matches.begin(), matches.end(), [&](const Match& m) {
        return static_cast<size_t>(m.model->type) == t.type &&
               cv::norm(m.centroid - t.centre) < 0.2;
      });
      ++parts;
      if (found == matches.end()) {
        ++missed;
        UNSCOPED_INFO("missed, seed " << seed << ": " << specs[t.type].name << " at " << t.centre.x
                                      << ", " << t.centre.y << " turned " << t.angle_deg << ", "
                                      << 100 * t.hidden << " % hidden");
      } else if (found->from_edges) {
        ++touching_found;
      }
    }
  }
  // Otherwise the scenes would not test parts in merged blobs.
  CHECK(touching_found >= 12);
  // A part of a blob is found from one of its corners or arcs whose pose
  // passes a first look at a few samples, and at this size the few that
  // show may pass it by a hair: which parts of these 48 are missed changes
  // with the compiler's rounding (none here with gcc, one with clang). When
  // the outline drawn whole counted its own boundary seam as lying off the
  // blob, 9 were.
  INFO(missed << " of " << parts << " missed");
  CHECK(missed <= 2);
}

TEST_CASE("a model's lines and arcs lie on the part it was trained from", "[vision][model]") {
  // Each primitive is moved from the pixel-centre contour onto the grey-level
  // edge, tenths of a pixel out. Through a short arc's few edge crossings a
  // circle may fit with its centre across the arc's chord: the arc then ran
  // round the far side of it, 5.8 to 15.7 px off these parts (outlines 120
  // and 200 px long, each at the turn where it did), and was searched for
  // where the part has nothing.
  struct Case {
    const char* file;
    double size_px;
    double turn_deg;
  };
  for (const Case& c :
       {Case{"shapes/tari1000/obj1_1.png", 120, 30}, Case{"shapes/tari1000/obj5_1.png", 200, 0},
        Case{"shapes/tari1000/obj6_1.png", 120, 30}}) {
    INFO(c.file << " at " << c.size_px << " px, turned " << c.turn_deg);
    const cv::Mat drawing = picksight::codecs::imread(
        std::string(PICKSIGHT_TEST_DATA_DIR) + "/" + c.file, cv::IMREAD_GRAYSCALE);
    REQUIRE_FALSE(drawing.empty());
    const auto type = ps::silhouetteFromDrawing("part", drawing, c.size_px);
    const int side = static_cast<int>(c.size_px * 1.5) + 300;
    const cv::Mat image = ps::renderSilhouetteAlone(type, side, ps::SilhouetteSceneOptions{}, 10,
                                                    nullptr, c.turn_deg);
    TrainOptions train;
    train.binarize = silhouetteBinarization();
    const auto model = trainModel(image, 0, "part", train);
    REQUIRE(model.ok());
    const auto regions = findRegions(binarize(image, train.binarize), {}, image);
    REQUIRE(regions.size() == 1);
    const Region& r = regions.front();
    std::vector<cv::Point> contour = r.outer;
    for (const auto& hole : r.hole_boundaries)
      contour.insert(contour.end(), hole.begin(), hole.end());
    // The farthest any point of the model's boundary lies from the pixel
    // centres of the part's contour: the edge lies half a pixel beyond them,
    // and a primitive up to the conformity (1 px) off its contour.
    double farthest = 0;
    for (const auto& loop : model.value().loops) {
      for (const auto& p : loop.primitives) {
        for (int k = 0; k <= 20; ++k) {
          const cv::Point2d at = r.centroid + p.pointAt(k / 20.0);
          double nearest = 1e9;
          for (const auto& q : contour) nearest = std::min(nearest, cv::norm(at - cv::Point2d(q)));
          farthest = std::max(farthest, nearest);
        }
      }
    }
    CHECK(farthest < 2.5);
  }
}
