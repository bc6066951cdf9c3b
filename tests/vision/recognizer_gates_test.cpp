// The recognizer's gates on look-alike part types that only one gate tells
// apart: a hole more or less, a size 6 % off, a difference inside the edge
// tolerance (the closer body wins), a part partly off its model (the
// verification threshold), nearly mirror-symmetric parts whose
// handedness lies in a small off-axis notch or key, and round parts that are
// each a little out of round (drawn, and photographed).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "picksight/codecs/codecs.hpp"

#include "drawn_parts.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/recognition/recognizer.hpp"
#include "picksight/vision/recognition/region_explanation.hpp"
#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/vision/segmentation/blob_features.hpp"
#include "picksight/vision/segmentation/regions.hpp"
#include "picksight/vision/training/part_training.hpp"

using namespace picksight::vision;
namespace pt = picksight::test;
namespace ps = picksight::synthetic;

namespace {
ps::Shape shapeOf(std::vector<pt::Loop> loops) { return pt::centred(ps::Shape{std::move(loops)}); }

PartModel trainDrawn(const ps::Shape& shape, int id, const std::string& name,
                     const TrainOptions& options = {}) {
  const cv::Mat grey = pt::drawParts(300, 300, {{shape, 150.3, 149.6, 17, false}}, 99 + id);
  auto outcome = trainModel(grey, id, name, options);
  INFO(name << ": " << (outcome ? std::string() : outcome.error().message));
  REQUIRE(outcome.ok());
  return outcome.value();
}

std::vector<Match> recognizeDrawn(const std::vector<pt::DrawnPart>& parts,
                                  const std::vector<const PartModel*>& models, uint64_t seed) {
  const cv::Mat grey = pt::drawParts(1000, 640, parts, seed);
  return recognize(findRegions(binarize(grey, {}), {}, grey), models);
}

const Match* matchAt(const std::vector<Match>& matches, const pt::DrawnPart& part) {
  for (const auto& m : matches) {
    if (std::hypot(m.centroid.x - part.x, m.centroid.y - part.y) < 5) return &m;
  }
  return nullptr;
}

std::vector<pt::DrawnPart> concat(std::vector<pt::DrawnPart> a,
                                  const std::vector<pt::DrawnPart>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// Every part in `parts` is reported whole (not as a touching part) as the
// model named `expected[i]`, or not at all where that is empty.
void checkReported(const std::vector<Match>& matches, const std::vector<pt::DrawnPart>& parts,
                   const std::vector<std::string>& expected) {
  for (size_t i = 0; i < parts.size(); ++i) {
    INFO("part " << i << " at " << parts[i].x << ", " << parts[i].y << " turned "
                 << parts[i].angle_deg << (parts[i].mirrored ? " mirrored" : ""));
    const Match* m = matchAt(matches, parts[i]);
    if (expected[i].empty()) {
      CHECK((m == nullptr || m->from_edges));
      continue;
    }
    REQUIRE(m);
    CHECK(m->model->name == expected[i]);
    CHECK_FALSE(m->from_edges);
  }
}

std::vector<std::string> names(size_t first_count, const std::string& first, size_t second_count,
                               const std::string& second) {
  std::vector<std::string> out(first_count, first);
  out.insert(out.end(), second_count, second);
  return out;
}

const ps::Shape& plate() {
  static const ps::Shape s = shapeOf({pt::rectLoop(120, 70)});
  return s;
}

// A 160 x 80 plate with a 5 x 5 px notch off its axes, in its top edge to
// the right: nearly mirror-symmetric.
const ps::Shape& notchedPlate() {
  static const ps::Shape s = shapeOf({{{-80, -40},
                                       {37.5, -40},
                                       {37.5, -35},
                                       {42.5, -35},
                                       {42.5, -40},
                                       {80, -40},
                                       {80, 40},
                                       {-80, 40}}});
  return s;
}
}  // namespace

TEST_CASE("a part with a hole is not taken for the same outline without one",
          "[vision][recognizer][gates]") {
  const ps::Shape holed = shapeOf({pt::rectLoop(120, 70), pt::circleLoop(6, {25, 0})});
  const PartModel plain_model = trainDrawn(plate(), 1, "plate");
  const PartModel holed_model = trainDrawn(holed, 2, "holed");
  const auto parts = concat(pt::partRow(plate(), 4, 100, 10), pt::partRow(holed, 4, 300, 40));
  // Only the plain plate trained: its outline fits the holed part at every
  // edge, and the hole count alone keeps the holed part out.
  checkReported(recognizeDrawn(parts, {&plain_model}, 1), parts, names(4, "plate", 4, ""));
  // Both trained: each is itself, whichever model comes first.
  checkReported(recognizeDrawn(parts, {&plain_model, &holed_model}, 2), parts,
                names(4, "plate", 4, "holed"));
  checkReported(recognizeDrawn(parts, {&holed_model, &plain_model}, 2), parts,
                names(4, "plate", 4, "holed"));
}

TEST_CASE("parts of one shape 6 percent apart in size are each their own type",
          "[vision][recognizer][gates]") {
  // A trapezoid (directed: its Hu invariants are all stable) with a 3 px
  // edge tolerance: each model's boundary lies within it of the other's,
  // only the area (12 % apart) tells them apart.
  const ps::Shape tab = shapeOf({{{-35, -20}, {35, -12}, {35, 12}, {-35, 20}}});
  const ps::Shape big_tab = pt::scaled(tab, 1.06);
  TrainOptions options;
  options.conformity = 2;
  const PartModel small_model = trainDrawn(tab, 1, "tab", options);
  const PartModel big_model = trainDrawn(big_tab, 2, "big tab", options);
  const auto parts = concat(pt::partRow(tab, 5, 100, 10), pt::partRow(big_tab, 5, 300, 40));
  const auto expected = names(5, "tab", 5, "big tab");
  checkReported(recognizeDrawn(parts, {&small_model, &big_model}, 3), parts, expected);
  checkReported(recognizeDrawn(parts, {&big_model, &small_model}, 4), parts, expected);
}

TEST_CASE("when two look-alike types both verify the closer body wins",
          "[vision][recognizer][gates]") {
  // Bores 0.75 px apart in radius: both boundary models verify on both parts
  // (within the 2 px edge tolerance), the Hu distance decides.
  const ps::Shape small_bore = shapeOf({pt::rectLoop(120, 70), pt::circleLoop(9, {25, 5})});
  const ps::Shape large_bore = shapeOf({pt::rectLoop(120, 70), pt::circleLoop(9.75, {25, 5})});
  const PartModel a = trainDrawn(small_bore, 1, "small bore");
  const PartModel b = trainDrawn(large_bore, 2, "large bore");
  const auto parts =
      concat(pt::partRow(small_bore, 4, 100, 10), pt::partRow(large_bore, 4, 300, 30));
  const auto expected = names(4, "small bore", 4, "large bore");
  for (const auto& order : {std::vector<const PartModel*>{&a, &b}, {&b, &a}}) {
    const auto matches = recognizeDrawn(parts, order, 5);
    checkReported(matches, parts, expected);
    for (const auto& m : matches) CHECK(m.score == 1.0);  // a tie: only the body decides
  }
}

TEST_CASE(
    "a part partly off its model is reported only down to the verification threshold and after "
    "better parts",
    "[vision][recognizer][gates]") {
  // A slot 5 px deep across most of each end: the plate's boundary misses
  // about a quarter of the part's, while area and Hu invariants pass.
  pt::Loop slotted{{-60, -35}, {60, -35}, {60, -28}, {55, -28}, {55, 28},   {60, 28},
                   {60, 35},   {-60, 35}, {-60, 28}, {-55, 28}, {-55, -28}, {-60, -28}};
  const ps::Shape slotted_plate = shapeOf({slotted});
  PartModel model = trainDrawn(plate(), 1, "plate");
  REQUIRE(model.verify_percent == 80);
  const auto parts =
      concat(pt::partRow(slotted_plate, 4, 100, 10), pt::partRow(plate(), 4, 300, 50));
  checkReported(recognizeDrawn(parts, {&model}, 6), parts, names(4, "", 4, "plate"));

  model.verify_percent = 60;
  const auto matches = recognizeDrawn(parts, {&model}, 6);
  checkReported(matches, parts, names(4, "plate", 4, "plate"));
  for (size_t i = 0; i < 4; ++i) {
    const Match* m = matchAt(matches, parts[i]);
    REQUIRE(m);
    CHECK(m->score >= 0.6);
    CHECK(m->score < 0.8);
  }
  // Best first: the plates that verify whole come before the slotted ones.
  REQUIRE(matches.size() == 8);
  CHECK(std::is_sorted(matches.begin(), matches.end(),
                       [](const Match& x, const Match& y) { return x.score > y.score; }));
  CHECK(matches.front().score > 0.95);
}

TEST_CASE("a nearly mirror-symmetric part is told from its mirror image by a small notch",
          "[vision][recognizer][mirror]") {
  // A 5 x 5 px notch off the axes of a 160 x 80 plate: under 3 % of the
  // outline differs from the mirror image.
  const ps::Shape& notched = notchedPlate();
  // A disc with a flat and a small key slot off the flat's axis.
  pt::Loop keyed;
  for (const auto& q : pt::circleLoop(50, {0, 0}, 180)) {
    const double deg = std::atan2(q.y, q.x) * 180 / M_PI;
    if (q.x > 30) {
      keyed.emplace_back(30, q.y);
    } else {
      keyed.push_back(deg > 60 && deg < 68 ? q * 0.88 : q);
    }
  }
  const ps::Shape keyed_disc = shapeOf({keyed});
  const PartModel notched_model = trainDrawn(notched, 1, "notched");
  const PartModel keyed_model = trainDrawn(keyed_disc, 2, "keyed");
  CHECK_FALSE(notched_model.body.mirror_symmetric);
  CHECK_FALSE(keyed_model.body.mirror_symmetric);
  // Every other part lies mirrored: only the others are the trained parts.
  const auto parts =
      concat(pt::partRow(notched, 5, 100, 10, true), pt::partRow(keyed_disc, 5, 300, 30, true));
  std::vector<std::string> expected;
  for (const auto& p : parts) {
    expected.push_back(p.mirrored ? "" : (p.y < 200 ? "notched" : "keyed"));
  }
  for (uint64_t seed : {7u, 8u}) {
    const auto matches = recognizeDrawn(parts, {&notched_model, &keyed_model}, seed);
    checkReported(matches, parts, expected);
    // Not even as a part touching nothing: a mirror image is no part.
    for (const auto& p : parts) {
      if (p.mirrored) CHECK(matchAt(matches, p) == nullptr);
    }
  }
}

TEST_CASE("a mirror-symmetric part is recognized whichever way it lies",
          "[vision][recognizer][mirror]") {
  const PartModel plate_model = trainDrawn(plate(), 1, "plate");
  const PartModel disc_model = trainDrawn(shapeOf({pt::circleLoop(45)}), 2, "disc");
  CHECK(plate_model.body.mirror_symmetric);
  CHECK(disc_model.body.mirror_symmetric);
  const auto parts = concat(pt::partRow(plate(), 5, 100, 10, true),
                            pt::partRow(shapeOf({pt::circleLoop(45)}), 5, 300, 30, true));
  checkReported(recognizeDrawn(parts, {&plate_model, &disc_model}, 9), parts,
                names(5, "plate", 5, "disc"));
}

TEST_CASE("a nearly mirror-symmetric part touching another is found and its mirror image is not",
          "[vision][recognizer][mirror][locator]") {
  // The notched plate with a corner of a plain plate against its left end:
  // one blob, so the touching-part locator places them. The notched plate's
  // mirror candidate verifies within a few percent of the direct one (the
  // hands differ only at the notch): the notch, not the scores, must decide,
  // as for separated parts.
  const PartModel notched_model = trainDrawn(notchedPlate(), 1, "notched");
  const PartModel plate_model = trainDrawn(plate(), 2, "plate");
  REQUIRE_FALSE(notched_model.body.mirror_symmetric);
  const std::vector<const PartModel*> models{&notched_model, &plate_model};
  // The plain plate's corner (60, 35) points along its angle + 30.26 deg.
  const double corner_deg = std::atan2(35.0, 60.0) * 180 / M_PI;
  const double corner_reach = std::hypot(60.0, 35.0);
  for (const bool mirrored : {false, true}) {
    for (const double deg : {20.0, 145.0, 250.0}) {
      INFO((mirrored ? "mirrored, " : "") << "turned " << deg);
      const double a = deg * M_PI / 180;
      // The plain plate to the left, its corner 1 px into the notched
      // plate's left end.
      const double back = 80 + corner_reach - 1;
      const pt::DrawnPart notched_part{notchedPlate(), 400, 320, deg, mirrored};
      const pt::DrawnPart plate_part{plate(), 400 - back * std::cos(a), 320 - back * std::sin(a),
                                     deg - corner_deg};
      const cv::Mat grey = pt::drawParts(800, 640, {notched_part, plate_part}, 11);
      const auto regions = findRegions(binarize(grey, {}), {}, grey);
      REQUIRE(regions.size() == 1);  // otherwise the locator is not asked
      const auto matches = recognize(regions, models);
      const Match* other = matchAt(matches, plate_part);
      REQUIRE(other);
      CHECK(other->model->name == "plate");
      CHECK(other->touching);
      const Match* m = matchAt(matches, notched_part);
      if (mirrored) {
        CHECK(m == nullptr);
      } else {
        REQUIRE(m);
        CHECK(m->model->name == "notched");
        CHECK(m->touching);
      }
    }
  }
}

// A round part as it comes from a press or a mould: a washer a few percent
// out of round, each piece its own way. Its small invariants (ellipticity,
// skew) change by orders of magnitude from piece to piece while the parts
// look alike: the shape test must not tell them apart, and must still tell
// a clearly oval part of the same area.
namespace {
ps::Shape washer(double aspect) {
  pt::Loop outer = pt::circleLoop(50);
  const double stretch = 1 / std::sqrt(aspect);
  for (auto& p : outer) p = {p.x * stretch, p.y / stretch};
  pt::Loop hole = pt::circleLoop(17);
  std::reverse(hole.begin(), hole.end());
  return shapeOf({outer, hole});
}
}  // namespace

TEST_CASE("round parts a few percent out of round are one type, a clearly oval one is not",
          "[vision][model]") {
  const PartModel model = trainDrawn(washer(0.99), 1, "washer");
  std::vector<pt::DrawnPart> parts;
  std::vector<std::string> expected;
  const double aspects[] = {1.0, 0.985, 0.975, 0.965, 0.955};
  for (int i = 0; i < 5; ++i) {
    parts.push_back({washer(aspects[i]), 110.0 + 190 * i, 140, 31.0 + 67 * i, false});
    expected.emplace_back("washer");
  }
  // Out of round by a quarter: a different part with the washer's area.
  for (int i = 0; i < 3; ++i) {
    parts.push_back({washer(0.75), 200.0 + 280 * i, 420, 12.0 + 55 * i, false});
    expected.emplace_back();
  }
  for (const uint64_t seed : {3, 4}) {
    INFO("seed " << seed);
    checkReported(recognizeDrawn(parts, {&model}, seed), parts, expected);
  }
  // The shape test (Hu) refuses the oval itself, not the boundary check
  // after it; the washers pass it.
  const cv::Mat grey = pt::drawParts(1000, 640, parts, 3);
  const auto regions = findRegions(binarize(grey, {}), {}, grey);
  for (const auto& part : parts) {
    const auto region = std::find_if(regions.begin(), regions.end(), [&](const Region& r) {
      return std::hypot(r.centroid.x - part.x, r.centroid.y - part.y) < 5;
    });
    REQUIRE(region != regions.end());
    const bool oval = part.y > 300;
    INFO((oval ? "oval" : "washer") << " at " << part.x << ", " << part.y);
    const RegionExplanation why = explainRegion(*region, {&model});
    CHECK(regionTestName(why.test) ==
          std::string(regionTestName(oval ? RegionTest::kHu : RegionTest::kPasses)));
  }
}

TEST_CASE("lone sweets in a photograph pass the shape test of one of them", "[vision][model]") {
  // Sweets photographed on white (tests/data/scenes/smarties.png): glossy,
  // lit from one side, none perfectly round. Their highlights are holes in
  // the binarized image, left out by a minimum hole area, as a cell set up
  // for glossy parts would.
  const cv::Mat grey = picksight::codecs::imread(
      std::string(PICKSIGHT_TEST_DATA_DIR) + "/scenes/smarties.png", cv::IMREAD_GRAYSCALE);
  REQUIRE_FALSE(grey.empty());
  TrainOptions options;
  options.regions.min_hole_area = 120;
  const auto regions = findRegions(binarize(grey, options.binarize), options.regions, grey);
  const auto at = [&](double x, double y) -> const Region* {
    for (const auto& r : regions) {
      if (std::hypot(r.centroid.x - x, r.centroid.y - y) < 6) return &r;
    }
    return nullptr;
  };
  const Region* taught = at(219, 306);
  REQUIRE(taught);
  auto trained = trainModelFromRegion(grey, *taught, 1, "sweet", options);
  REQUIRE(trained.ok());
  // The sweets that lie alone, whole and clear of their own shadow.
  const cv::Point2d lone[] = {{294, 320}, {347, 238}, {377, 82}, {269, 117}, {205, 211}};
  for (const auto& p : lone) {
    INFO("sweet at " << p.x << ", " << p.y);
    const Region* r = at(p.x, p.y);
    REQUIRE(r);
    CHECK(huDistance(trained->body, logHu(huInvariants(r->moments))) <= trained->body.hu_tolerance);
  }
}
