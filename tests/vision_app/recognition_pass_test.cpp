// The cell's recognition pass: each model judges holes with the minimum
// hole area it was trained with, whatever the cell's setting, and
// `LOCATE <type>` does not report a part clearly closer to another type's
// model, and WHY says so. Drawn scenes, the vision app's own locate path.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "../vision/drawn_parts.hpp"
#include "picksight/cell/vision_service.hpp"
#include "picksight/results/request_record.hpp"
#include "picksight/vision/recognition/recognition_pass.hpp"

using namespace picksight;
using namespace picksight::cell;
using namespace picksight::store;
using picksight::test::DrawnPart;

namespace {
// A plate with no hole of its own, and a perforated plate with four holes
// smaller than 50 px (traced area about 40 px each).
const synthetic::Shape kPlate{{test::rectLoop(200, 120)}};
synthetic::Shape perforated() {
  synthetic::Shape s{{test::rectLoop(150, 150)}};
  for (double x : {-40.0, 40.0})
    for (double y : {-40.0, 40.0}) s.loops.push_back(test::circleLoop(4.5, {x, y}, 24));
  return s;
}
// Two specks of dust inside a plate: holes of about 20 px.
synthetic::Shape speckledPlate() {
  synthetic::Shape s = kPlate;
  s.loops.push_back(test::circleLoop(3, {-50, 10}, 16));
  s.loops.push_back(test::circleLoop(3, {40, -25}, 16));
  return s;
}

VisionOptions withMinHoleArea(double area) {
  VisionOptions o;
  o.regions.min_hole_area = area;
  return o;
}

// The model of the single part of `part` drawn alone, trained with `options`.
vision::PartModel learned(const DrawnPart& part, int type, const std::string& name,
                          const VisionOptions& options) {
  const cv::Mat image = test::drawParts(640, 480, {part}, 3);
  auto model =
      learnInImage(image, {}, options, std::make_shared<const ModelList>(), type, name, {});
  REQUIRE(model);
  return model->model;
}

const LocatedPart* near(const std::vector<LocatedPart>& parts, double x, double y) {
  for (const auto& p : parts)
    if (std::hypot(p.x - x, p.y - y) < 1) return &p;
  return nullptr;
}
}  // namespace

TEST_CASE("each model counts holes with the minimum hole area it was trained with",
          "[locate][min_hole_area]") {
  // The plate learned where specks are dust (50 px), the perforated plate
  // where every hole counts (0).
  const auto plate = learned({kPlate, 320, 240, 10}, 1, "plate", withMinHoleArea(50));
  const auto holes = learned({perforated(), 320, 240, 0}, 2, "perforated", withMinHoleArea(0));
  REQUIRE(plate.min_hole_area == 50);
  REQUIRE(plate.body.holes == 0);
  REQUIRE(holes.min_hole_area == 0);
  REQUIRE(holes.body.holes == 4);
  const auto models = std::make_shared<const ModelList>(ModelList{plate, holes});

  // A speckled plate and a perforated one, in cells set either way.
  const cv::Mat scene = test::drawParts(
      1280, 720, {{speckledPlate(), 350, 300, 30}, {perforated(), 900, 400, 20}}, 9);
  const Frame frame = frameFromImage(scene, "cam", 1);
  for (double cell_min : {0.0, 50.0}) {
    INFO("cell --min-hole-area " << cell_min);
    const VisionOptions cell = withMinHoleArea(cell_min);
    for (int type : {-1, 1, 2}) {
      INFO("LOCATE " << type);
      const auto outcome = locateInFrame(frame, cell, models, type);
      const LocatedPart* p = near(outcome.parts, 350, 300);
      const LocatedPart* h = near(outcome.parts, 900, 400);
      CHECK(outcome.parts.size() == (type < 0 ? 2u : 1u));
      if (type != 2) {
        REQUIRE(p);
        CHECK(p->type == 1);
      }
      if (type != 1) {
        REQUIRE(h);
        CHECK(h->type == 2);
      }
    }
  }
}

TEST_CASE("the cell's region settings are the smallest of its own and its models'",
          "[locate][min_hole_area]") {
  vision::RegionOptions cell;
  cell.min_area = 50;
  cell.min_hole_area = 30;
  std::vector<vision::PartModel> models(2);
  models[0].min_hole_area = 50;
  models[0].min_region_area = 80;
  models[1].min_hole_area = 10;
  models[1].min_region_area = 0;  // an old file: not recorded
  const auto o = vision::regionOptionsFor(cell, models);
  CHECK(o.min_hole_area == 10);
  CHECK(o.min_area == 50);
  models[1].min_region_area = 20;
  CHECK(vision::regionOptionsFor(cell, models).min_area == 20);
  CHECK(vision::regionOptionsFor(cell, {}).min_hole_area == 30);
}

TEST_CASE("LOCATE of one type does not report a part clearly closer to another type",
          "[locate][prescreen]") {
  // Two types of nearly one area: a bar and the same bar with a notch
  // (2 % less area). Each passes the other's area, hole, shape and boundary
  // tests, so only the comparison across types tells them apart.
  const synthetic::Shape bar{{test::rectLoop(200, 100)}};
  const synthetic::Shape notched{
      {{{-100, -50}, {100, -50}, {100, 50}, {15, 50}, {15, 22}, {-15, 22}, {-15, 50}, {-100, 50}}}};
  const auto bar_model = learned({test::centred(bar), 320, 240, 0}, 1, "bar", {});
  const auto notched_model = learned({test::centred(notched), 320, 240, 0}, 2, "notched", {});
  const cv::Mat scene = test::drawParts(1280, 720,
                                        {{test::centred(bar), 250, 200, 15},
                                         {test::centred(bar), 700, 520, 200},
                                         {test::centred(notched), 650, 200, 40},
                                         {test::centred(notched), 1050, 450, 300}},
                                        11);
  const Frame frame = frameFromImage(scene, "cam", 1);

  // Each type's models alone accept both kinds: the confusion the screen
  // is there for. The bar model's region tests pass one notched bar and
  // fail the other on the pose its notch skews (78 % verified); the blob
  // search finds that one, judged as a lone part by the verify fraction
  // alone though 5 % of the bar's outline crosses the notch, where a
  // look-alike on a part of a merged blob would be refused.
  const auto bars_only =
      locateInFrame(frame, {}, std::make_shared<const ModelList>(ModelList{bar_model}), 1);
  CHECK(bars_only.parts.size() == 4);
  const auto notched_only =
      locateInFrame(frame, {}, std::make_shared<const ModelList>(ModelList{notched_model}), 2);
  CHECK(notched_only.parts.size() == 4);

  const auto both = std::make_shared<const ModelList>(ModelList{bar_model, notched_model});
  const auto bars = locateInFrame(frame, {}, both, 1);
  INFO("LOCATE 1 found " << bars.parts.size());
  CHECK(bars.parts.size() == 2);
  CHECK(near(bars.parts, 250, 200));
  CHECK(near(bars.parts, 700, 520));
  // The two notched bars, left out as type 2 (WHY names them so).
  REQUIRE(bars.scene.screened_out.size() == 2);
  for (const auto& out : bars.scene.screened_out) {
    CHECK(out.closer_type == 2);
    const auto& r = bars.scene.regions[static_cast<size_t>(out.region)];
    CHECK(std::min(std::hypot(r.centroid.x - 650, r.centroid.y - 200),
                   std::hypot(r.centroid.x - 1050, r.centroid.y - 450)) < 1);
  }
  const auto notches = locateInFrame(frame, {}, both, 2);
  INFO("LOCATE 2 found " << notches.parts.size());
  CHECK(notches.parts.size() == 2);
  CHECK(near(notches.parts, 650, 200));
  CHECK(near(notches.parts, 1050, 450));
  // WHY names them as the other type.
  results::RequestRecord record;
  record.request = "LOCATE";
  record.asked_type = 1;
  record.locate = bars;
  for (size_t i = 0; i < bars.parts.size(); ++i) record.pick.parts.push_back(i);
  INFO("WHY: " << record.why());
  size_t named = 0;
  for (const auto& r : record.rejections()) named += r.test == "other type" && r.nearest_type == 2;
  CHECK(named == 2);
  CHECK(record.why().find(" is type 2 not 1") != std::string::npos);

  // LOCATE ALL labels each as its own type.
  const auto all = locateInFrame(frame, {}, both, -1);
  REQUIRE(all.parts.size() == 4);
  for (const auto& p : all.parts) {
    const bool is_bar = near(bars.parts, p.x, p.y) != nullptr;
    CHECK(p.type == (is_bar ? 1 : 2));
  }
}
