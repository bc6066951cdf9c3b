// Explanations (the results stream's rejections, WHY) never disagree with
// recognition: on rendered scenes of public silhouettes among their mirror
// images and 0.8x / 1.25x copies, with one type whose parts carry pinholes
// its model was trained to ignore, every region the cell's recognition pass
// reports a part from passes that model's tests, and every region it
// reports nothing from fails a test: "mirror" for a mirror image, "scale"
// for a scaled copy. And WHY reads the scale of a copy. On a belt the
// threshold speckles, WHY names the near misses first, then the blotches
// plainly unlike any part while the line has room, and counts the rest;
// where "plainly unlike" begins.
#include <catch2/catch.hpp>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>
#include "picksight/codecs/codecs.hpp"

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
      const cv::Mat drawing = picksight::codecs::imread(
          std::string(PICKSIGHT_TEST_DATA_DIR) + "/" + spec.file, cv::IMREAD_GRAYSCALE);
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

namespace {
// The low-contrast front light (30 grey levels between part and belt) of
// the front-light benchmark, whose belt the default threshold speckles.
ps::SilhouetteSceneOptions lowContrast() {
  ps::SilhouetteSceneOptions look;
  REQUIRE(ps::frontLightCondition("low-contrast", &look.front, &look.part_level,
                                  &look.background_level));
  return look;
}

// `type`, `size_px` across, taught alone under `look` with LEARN ... AT.
std::shared_ptr<const store::ModelList> teachAlone(const ps::SilhouetteType& type, double size_px,
                                                   const ps::SilhouetteSceneOptions& look) {
  cv::Point2d at;
  const cv::Mat teach = ps::renderSilhouetteAlone(type, 645, look, 7, &at, 30);
  const double half = 0.6 * size_px;
  const cv::Rect box(static_cast<int>(at.x - half), static_cast<int>(at.y - half),
                     static_cast<int>(2 * half), static_cast<int>(2 * half));
  auto learned = cell::learnInImage(teach, {}, {}, std::make_shared<const store::ModelList>(), 1,
                                    type.name, box);
  INFO((learned.ok() ? std::string() : learned.error().message));
  REQUIRE(learned.ok());
  return std::make_shared<const store::ModelList>(store::ModelList{learned->model});
}
}  // namespace

TEST_CASE(
    "WHY names the near misses on a speckled belt first and counts the regions unlike any part it "
    "leaves unsaid",
    "[vision][why][unlike]") {
  // The bug: on a belt at 30 grey levels every blotch the threshold took in
  // got its own sentence, and the parts' mirror images, the regions worth a
  // look, were pushed out of WHY's line among them.
  const ps::SilhouetteSceneOptions look = lowContrast();
  const ps::SilhouetteType ell = ps::silhouetteFromPartType("l_shape", 110);
  const auto models = teachAlone(ell, 110, look);
  ps::SilhouetteSceneOptions o = look;
  o.width = 1280;
  o.height = 960;
  o.parts = 8;
  o.distractor_share = 0.5;  // copies and mirror images: near misses
  o.seed = 4;
  const ps::SilhouetteScene scene({ell}, {true}, o);
  // The vision app's defaults: the window it picks speckles the belt.
  const auto outcome =
      cell::locateInFrame(frameFromImage(scene.render(0), "cam", 1), {}, models, 1);
  results::RequestRecord record;
  record.request = "LOCATE";
  record.asked_type = 1;
  record.locate = outcome;
  for (size_t i = 0; i < outcome.parts.size(); ++i) record.pick.parts.push_back(i);
  const std::string why = record.why();
  INFO("WHY: " << why);

  int near = 0;
  int remedies = 0;
  std::vector<std::string> near_texts;
  int unlike = 0;
  for (const auto& r : record.rejections()) {
    const pv::Region& region = outcome.scene.regions[r.region];
    const bool drawn = drawnAt(scene, region.centroid) != nullptr;
    INFO(r.text << (drawn ? " (a drawn part)" : " (the belt)"));
    // Every part drawn, the mirror images and copies among them, is a near
    // miss, but where the threshold left a hole in it: refused for its holes
    // first, it is judged by its shape, which a hole or a stretch of the belt
    // joined may take far off the part's (a 1.25 copy with a hole, its shape
    // distance 3.4, in clang's build, whose binarization differs by a few
    // pixels; gcc's left it none).
    if (drawn && r.test != "holes") CHECK_FALSE(r.unlike_any_part);
    if (r.unlike_any_part) {
      ++unlike;
      CHECK(r.remedy_key.empty());
    } else {
      ++near;
      near_texts.push_back(r.text);
      remedies += r.remedy_key.empty() ? 0 : 1;
    }
  }
  // The belt gives many such regions; the scene's copies and mirror images
  // are near misses (a copy with a speckle's hole in it too), some with a
  // remedy (two in gcc's build, one in clang's: its copies took holes).
  CHECK(unlike >= 10);
  CHECK(near >= 3);
  CHECK(remedies >= 1);
  // The near misses' sentences in region order, then the belt's while the
  // line has room, then how many of those it left unsaid.
  std::string near_part = "OK " + std::to_string(record.rejections().size());
  for (size_t i = 0; i < near_texts.size(); ++i) near_part += (i ? "; " : " ") + near_texts[i];
  REQUIRE(why.rfind(near_part + "; ", 0) == 0);
  CHECK(why.size() <= results::kMaxWhyBytes);
  std::string rest = why.substr(near_part.size() + 2);
  int said = 0;
  for (const auto& r : record.rejections()) {
    if (!r.unlike_any_part || rest.rfind(r.text + "; ", 0) != 0) continue;
    rest = rest.substr(r.text.size() + 2);
    ++said;
  }
  CHECK(said >= 1);
  CHECK(rest == std::to_string(unlike - said) + " more regions unlike any part");
}

TEST_CASE("a region is unlike a part twice its tolerance off its area or shape, not closer",
          "[vision][why][unlike]") {
  const ps::Shape l_shape =
      test::centred(ps::Shape{{{{0, 0}, {160, 0}, {160, 50}, {50, 50}, {50, 110}, {0, 110}}}});
  auto trained = pv::trainModel(test::drawParts(640, 480, {{l_shape, 320, 240, 0}}, 3), 1, "ell");
  REQUIRE(trained.ok());
  const pv::PartModel& model = trained.value();
  REQUIRE(model.body.area_tolerance == Approx(0.1));
  // Copies of the part with three small holes it has not (so that no copy
  // of another size is read in them, and their area decides) at areas 1.18
  // and 1.22 times its own (the model allows 1.1), and at 1.4; plain copies
  // at 1.22 (a copy of another size), 2.6 and 0.4; a bar of its area; and
  // pieces the frame's border cuts: a bar of half its area, the same with a
  // hole, a square cut to twice its area.
  ps::Shape speckled = l_shape;
  for (const double x : {0.0, 30.0, 60.0}) speckled.loops.push_back(test::rectLoop(5, 5, {x, -15}));
  const cv::Mat image = test::drawParts(
      1280, 720,
      {{test::scaled(speckled, std::sqrt(1.18)), 250, 200, 20},
       {test::scaled(speckled, std::sqrt(1.22)), 650, 200, 20},
       {test::scaled(speckled, std::sqrt(1.4)), 950, 600, 20},
       {test::scaled(l_shape, std::sqrt(1.22)), 600, 420, 20},
       {test::scaled(l_shape, std::sqrt(2.6)), 330, 520, 20},
       {test::scaled(l_shape, std::sqrt(0.4)), 1000, 420, 20},
       {test::centred(ps::Shape{{test::rectLoop(230, 48)}}), 1000, 200, 0},
       {test::centred(ps::Shape{{test::rectLoop(100, 70)}}), 1260, 500, 0},
       {test::centred(ps::Shape{{test::rectLoop(100, 70), test::rectLoop(20, 20, {20, 0})}}), 20,
        500, 0},
       {test::centred(ps::Shape{{test::rectLoop(200, 200)}}), 700, 700, 0}},
      5);
  pv::RegionOptions keep;
  keep.keep_border_regions = true;  // as LOCATE keeps those large enough to hold a part
  const auto regions = pv::findRegions(pv::binarize(image, {}), keep, image);
  const auto at = [&](double x, double y) -> const pv::Region& {
    for (const auto& r : regions)
      if (std::hypot(r.centroid.x - x, r.centroid.y - y) < 40 ||
          (r.touches_border &&
           r.bbox.contains(cv::Point(static_cast<int>(x), static_cast<int>(y)))))
        return r;
    FAIL("no region at " << x << ", " << y);
    return regions.front();
  };
  const std::vector<const pv::PartModel*> models{&model};
  CHECK_FALSE(pv::unlikeEveryModel(at(250, 200), models));
  CHECK(pv::unlikeEveryModel(at(650, 200), models));
  CHECK(pv::unlikeEveryModel(at(950, 600), models));
  // Twice the tolerance off its area, but the part's shape and holes: a
  // copy of another size, a near miss.
  CHECK_FALSE(pv::unlikeEveryModel(at(600, 420), models));
  // The part's shape, but larger or smaller than any copy of it is.
  CHECK(pv::unlikeEveryModel(at(330, 520), models));
  CHECK(pv::unlikeEveryModel(at(1000, 420), models));
  // Of the part's area but not its shape.
  CHECK(pv::unlikeEveryModel(at(1000, 200), models));
  // Cut by the border: smaller than the part, no hole, may be part of one;
  // too large, or with a hole the part has not, is none.
  CHECK_FALSE(pv::unlikeEveryModel(at(1260, 500), models));
  CHECK(pv::unlikeEveryModel(at(20, 500), models));
  CHECK(pv::unlikeEveryModel(at(700, 700), models));
  // A tolerance tightened below LEARN's moves "far" no nearer: the copy at
  // 1.18 stays a near miss.
  pv::PartModel tight = model;
  tight.body.area_tolerance = 0.01;
  tight.body.hu_tolerance = 1e-6;
  CHECK_FALSE(pv::unlikeEveryModel(at(250, 200), {&tight}));
  CHECK(pv::unlikeEveryModel(at(650, 200), {&tight}));
  // Another model near it keeps it a near miss: unlike every part, not one.
  pv::PartModel wider = model;
  wider.type = 2;
  wider.body.area_tolerance = 0.2;
  CHECK_FALSE(pv::unlikeEveryModel(at(650, 200), {&model, &wider}));
  CHECK_FALSE(pv::unlikeEveryModel(at(650, 200), {}));
}
