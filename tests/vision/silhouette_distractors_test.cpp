// Public silhouettes (Tari-1000) and the repository's L shape among their own
// mirror images and 0.8x / 1.25x copies: only the parts as trained are
// reported, each where it was drawn.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "picksight/synthetic/silhouette_scene.hpp"
#include "picksight/vision/binarize.hpp"
#include "picksight/vision/part_model.hpp"
#include "picksight/vision/recognizer.hpp"
#include "picksight/vision/regions.hpp"

using namespace picksight::vision;
namespace ps = picksight::synthetic;

namespace {
// A report this close to a drawn part's centroid is about that part; parts
// lie gap_px (8) apart, so no report is near two.
constexpr double kNearPx = 12;

struct Spec {
  std::string name;
  std::string file;  // under the test data directory; empty: the own part type
  double size_px;
};

// Chiral shapes (so that mirrored copies are drawn), curved and polygonal;
// the turtle and the L shape are those a layout once made go missing.
const std::vector<Spec>& specs() {
  static const std::vector<Spec> s = {
      {"turtle", "shapes/tari1000/obj4_1.png", 170},
      {"bottle", "shapes/tari1000/obj32_1.png", 190},
      {"frog", "shapes/tari1000/obj20_1.png", 180},
      {"l_shape", "", 160},
  };
  return s;
}
}  // namespace

TEST_CASE("mirrored and rescaled public silhouettes are never reported", "[vision][mirror]") {
  BinarizeOptions binarize_options;
  binarize_options.adaptive_window = 400;  // wider than any part, as the bench sets it
  TrainOptions train;
  train.binarize = binarize_options;
  const ps::SilhouetteSceneOptions look;

  std::vector<ps::SilhouetteType> types;
  std::vector<PartModel> models;
  std::vector<bool> chiral;
  for (size_t i = 0; i < specs().size(); ++i) {
    const Spec& spec = specs()[i];
    if (spec.file.empty()) {
      types.push_back(ps::silhouetteFromPartType(spec.name, spec.size_px));
    } else {
      const std::string path = std::string(PICKSIGHT_TEST_DATA_DIR) + "/" + spec.file;
      const cv::Mat drawing = cv::imread(path, cv::IMREAD_GRAYSCALE);
      INFO(path);
      REQUIRE_FALSE(drawing.empty());
      types.push_back(ps::silhouetteFromDrawing(spec.name, drawing, spec.size_px));
    }
    const int side = static_cast<int>(spec.size_px * 1.5) + 300;
    const cv::Mat image = ps::renderSilhouetteAlone(types.back(), side, look, 7 + i, nullptr);
    auto outcome = trainModel(image, static_cast<int>(i), spec.name, train);
    INFO(spec.name << ": " << (outcome ? std::string() : outcome.error().message));
    REQUIRE(outcome.ok());
    chiral.push_back(!outcome.value().body.mirror_symmetric);
    models.push_back(outcome.value());
  }
  // Every type here is chiral: each gets mirrored distractors too.
  for (size_t i = 0; i < specs().size(); ++i) {
    INFO(specs()[i].name);
    CHECK(chiral[i]);
  }
  std::vector<const PartModel*> list;
  for (const auto& m : models) list.push_back(&m);

  int distractors = 0;
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    ps::SilhouetteSceneOptions o = look;
    o.width = 1280;
    o.height = 720;
    o.parts = 12;
    o.seed = seed;
    o.distractor_share = 0.5;
    const ps::SilhouetteScene scene(types, chiral, o);
    const cv::Mat grey = scene.render(0);
    const auto matches = recognize(findRegions(binarize(grey, binarize_options), {}, grey), list);
    std::vector<int> found(scene.truth().size(), 0);
    for (const auto& m : matches) {
      INFO("seed " << seed << ": " << m.model->name << " reported at " << m.centroid.x << ", "
                   << m.centroid.y);
      const ps::SilhouettePart* near = nullptr;
      size_t index = 0;
      for (size_t i = 0; i < scene.truth().size(); ++i) {
        const auto& t = scene.truth()[i];
        if (std::hypot(t.centre.x - m.centroid.x, t.centre.y - m.centroid.y) < kNearPx) {
          near = &t;
          index = i;
        }
      }
      REQUIRE(near);
      INFO("drawn there: " << specs()[near->type].name << " kind " << static_cast<int>(near->kind));
      CHECK(near->kind == ps::PartKind::kTrue);
      CHECK(static_cast<size_t>(m.model->type) == near->type);
      found[index] += 1;
    }
    for (size_t i = 0; i < scene.truth().size(); ++i) {
      const auto& t = scene.truth()[i];
      if (t.kind != ps::PartKind::kTrue) {
        ++distractors;
        continue;
      }
      INFO("seed " << seed << ": " << specs()[t.type].name << " at " << t.centre.x << ", "
                   << t.centre.y << " turned " << t.angle_deg);
      CHECK(found[i] == 1);
    }
  }
  // Otherwise the test would test nothing.
  CHECK(distractors >= 6);
}
