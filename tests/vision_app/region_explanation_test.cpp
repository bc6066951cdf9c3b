// Explanations (the results stream's rejections, WHY) never disagree with
// recognition: on rendered scenes of public silhouettes among their mirror
// images and 0.8x / 1.25x copies, with one type whose parts carry pinholes
// its model was trained to ignore, every region the cell's recognition pass
// reports a part from passes that model's tests, and every region it
// reports nothing from fails a test: "mirror" for a mirror image, "scale"
// for a scaled copy. And WHY reads the scale of a copy.
#include <catch2/catch.hpp>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "../vision/drawn_parts.hpp"
#include "picksight/cell/vision_service.hpp"
#include "picksight/common/frame.hpp"
#include "picksight/results/request_record.hpp"
#include "picksight/synthetic/silhouette_scene.hpp"
#include "picksight/vision/recognition/recognition_pass.hpp"
#include "picksight/vision/recognition/region_explanation.hpp"
#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/vision/training/part_training.hpp"

using namespace picksight;
namespace ps = picksight::synthetic;
namespace pv = picksight::vision;

namespace {
// A region this close to a drawn part's centroid is that part; parts lie
// gap_px (8) apart.
constexpr double kNearPx = 12;
// The pinholes: about 28 px drawn (44 px on a 1.25x copy), under the minimum hole
// area the pinned type is trained with.
constexpr double kPinholeRadiusPx = 3.0;
constexpr double kPinnedMinHoleArea = 80;

struct Spec {
  std::string name;
  std::string file;  // under the test data directory; empty: the own part type
  double size_px;
  bool pinholes;
};

const std::vector<Spec>& specs() {
  static const std::vector<Spec> s = {
      {"turtle", "shapes/tari1000/obj4_1.png", 170, false},
      {"frog", "shapes/tari1000/obj20_1.png", 180, false},
      {"l_shape", "", 160, false},
      {"bottle", "shapes/tari1000/obj32_1.png", 190, true},
  };
  return s;
}

// The type with a pinhole punched at its deepest point.
ps::SilhouetteType withPinhole(ps::SilhouetteType type) {
  cv::Mat distance;
  cv::distanceTransform(type.mask, distance, cv::DIST_L2, 3);
  cv::Point deepest;
  cv::minMaxLoc(distance, nullptr, nullptr, nullptr, &deepest);
  cv::circle(type.mask, deepest, static_cast<int>(kPinholeRadiusPx * ps::kSilhouetteSupersample),
             cv::Scalar(0), cv::FILLED);
  return type;
}

const ps::SilhouettePart* drawnAt(const ps::SilhouetteScene& scene, cv::Point2d p) {
  for (const auto& t : scene.truth())
    if (std::hypot(t.centre.x - p.x, t.centre.y - p.y) < kNearPx) return &t;
  return nullptr;
}
}  // namespace

TEST_CASE("explanations agree with recognition on every separated region",
          "[vision][why][mirror]") {
  pv::BinarizeOptions binarize;
  binarize.adaptive_window = 400;  // wider than any part, as the bench sets it
  const ps::SilhouetteSceneOptions look;
  std::vector<ps::SilhouetteType> types;
  std::vector<bool> chiral;
  std::vector<pv::PartModel> models;
  for (size_t i = 0; i < specs().size(); ++i) {
    const Spec& spec = specs()[i];
    INFO(spec.name);
    if (spec.file.empty()) {
      types.push_back(ps::silhouetteFromPartType(spec.name, spec.size_px));
    } else {
      const cv::Mat drawing =
          cv::imread(std::string(PICKSIGHT_TEST_DATA_DIR) + "/" + spec.file, cv::IMREAD_GRAYSCALE);
      REQUIRE_FALSE(drawing.empty());
      types.push_back(ps::silhouetteFromDrawing(spec.name, drawing, spec.size_px));
    }
    if (spec.pinholes) types.back() = withPinhole(types.back());
    pv::TrainOptions train;
    train.binarize = binarize;
    train.regions.min_hole_area = spec.pinholes ? kPinnedMinHoleArea : 0;
    const int side = static_cast<int>(spec.size_px * 1.5) + 300;
    const cv::Mat image = ps::renderSilhouetteAlone(types.back(), side, look, 7 + i, nullptr);
    auto model = pv::trainModel(image, static_cast<int>(i), spec.name, train);
    REQUIRE(model.ok());
    REQUIRE(model.value().body.holes == 0);
    chiral.push_back(!model.value().body.mirror_symmetric);
    models.push_back(model.value());
  }
  std::vector<const pv::PartModel*> all;
  for (const auto& m : models) all.push_back(&m);

  int mirrors = 0;
  int copies = 0;
  int pinned = 0;  // parts recognized whose region holds a hole their model ignores
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    ps::SilhouetteSceneOptions o = look;
    o.width = 1280;
    o.height = 720;
    o.parts = 12;
    o.seed = seed;
    o.distractor_share = 0.5;
    const ps::SilhouetteScene scene(types, chiral, o);
    const cv::Mat grey = scene.render(0);
    const auto regions =
        pv::findRegions(pv::binarize(grey, binarize), pv::regionOptionsFor({}, models), grey);
    const auto pass = pv::recognizeParts(regions, models, -1);
    for (size_t i = 0; i < regions.size(); ++i) {
      const pv::Region& region = regions[i];
      const ps::SilhouettePart* drawn = drawnAt(scene, region.centroid);
      INFO("seed " << seed << " region " << i << " at " << region.centroid.x << ", "
                   << region.centroid.y);
      REQUIRE(drawn);
      INFO("drawn: " << specs()[drawn->type].name << " kind " << static_cast<int>(drawn->kind));
      bool reported = false;
      for (const auto& m : pass.matches) {
        if (m.region != i) continue;
        reported = true;
        INFO("reported as " << m.model->name);
        CHECK_FALSE(m.from_edges);
        CHECK(pv::explainRegion(region, {m.model}).test == pv::RegionTest::kPasses);
        if (pv::holesAtLeast(region, m.model->min_hole_area) != region.holes) ++pinned;
      }
      CHECK(reported == (drawn->kind == ps::PartKind::kTrue));
      if (reported) continue;
      const pv::RegionExplanation e = pv::explainRegion(region, all);
      INFO("explained: " << pv::regionTestName(e.test) << " of "
                         << (e.nearest ? e.nearest->name : "none"));
      CHECK(e.test != pv::RegionTest::kPasses);
      REQUIRE(e.nearest);
      CHECK(static_cast<size_t>(e.nearest->type) == drawn->type);
      if (drawn->kind == ps::PartKind::kMirrored) {
        CHECK(e.test == pv::RegionTest::kMirror);
        ++mirrors;
      } else {
        CHECK(e.test == pv::RegionTest::kScale);
        ++copies;
      }
    }
  }
  // Otherwise the test would test nothing.
  CHECK(mirrors >= 3);
  CHECK(copies >= 3);
  CHECK(pinned >= 1);
}

TEST_CASE("WHY reads the scale of a copy and names a mirror image", "[vision][why]") {
  const ps::Shape l_shape =
      test::centred(ps::Shape{{{{0, 0}, {160, 0}, {160, 50}, {50, 50}, {50, 110}, {0, 110}}}});
  auto trained = pv::trainModel(test::drawParts(640, 480, {{l_shape, 320, 240, 0}}, 3), 1, "ell");
  REQUIRE(trained.ok());
  const auto models = std::make_shared<const store::ModelList>(store::ModelList{trained.value()});
  const cv::Mat scene = test::drawParts(1280, 720,
                                        {{l_shape, 250, 250, 30},
                                         {test::scaled(l_shape, 1.25), 700, 250, 100},
                                         {l_shape, 450, 550, 70, true}},
                                        7);
  const auto outcome = cell::locateInFrame(frameFromImage(scene, "cam", 1), {}, models, 1);
  REQUIRE(outcome.parts.size() == 1);
  results::RequestRecord record;
  record.request = "LOCATE";
  record.asked_type = 1;
  record.locate = outcome;
  record.pick.parts.push_back(0);
  const std::string why = record.why();
  INFO("WHY: " << why);
  CHECK(why.rfind("OK 2 ", 0) == 0);
  CHECK(why.find(" scaled 1.25x outside 0.95..1.05 of type 1") != std::string::npos);
  CHECK(why.find(" mirror of type 1") != std::string::npos);
  int scale = 0;
  for (const auto& r : record.rejections()) {
    if (r.test != "scale") continue;
    ++scale;
    CHECK(r.measured == Approx(1.25).epsilon(0.01));
    CHECK(r.nearest_name == "ell");
  }
  CHECK(scale == 1);
}
