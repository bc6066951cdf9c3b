// Part models and recognition on synthetic scenes with exact ground truth:
// training errors, symmetry, mirror images, size pairs, rotation from the
// trained pose, boundary primitives.
#include <catch2/catch.hpp>

#include <algorithm>

#include "recognition_support.hpp"

#include <map>
#include <opencv2/imgproc.hpp>

#include "picksight/common/angles.hpp"
#include "picksight/synthetic/scene.hpp"
#include "picksight/vision/models/part_model.hpp"
#include "picksight/vision/recognition/recognizer.hpp"
#include "picksight/vision/segmentation/regions.hpp"
#include "picksight/vision/training/part_training.hpp"

using namespace picksight::vision;
namespace ps = picksight::synthetic;
using picksight::angleDiffDeg;

namespace {
ps::SceneOptions scene(int width, int height, int parts, uint64_t seed,
                       std::vector<std::string> types) {
  ps::SceneOptions o = ps::sceneOptions(width, height, parts, seed, std::move(types));
  o.blur_sigma = 0.7;
  return o;
}

using picksight::test::nearest;
using picksight::test::Trained;

Trained train(const std::string& type, int id) {
  return picksight::test::trainOn(scene(400, 400, 1, 77 + static_cast<uint64_t>(id), {type}), id,
                                  type);
}

std::vector<Match> recognizeScene(const ps::SceneRenderer& s,
                                  const std::vector<const PartModel*>& models) {
  return picksight::test::recognizeFrame(s, 1, models);
}
}  // namespace

TEST_CASE("training needs exactly one part", "[vision][model]") {
  cv::Mat empty(200, 200, CV_8UC1, cv::Scalar(200));
  auto outcome = trainModel(empty, 1, "x");
  CHECK_FALSE(outcome.ok());
  CHECK(outcome.error().message.find("no part") != std::string::npos);
  const ps::SceneRenderer two(scene(640, 480, 2, 3, {"rectangle"}));
  outcome = trainModel(two.render(0), 1, "x");
  CHECK_FALSE(outcome.ok());
  CHECK(outcome.error().message.find("2 parts") != std::string::npos);
}

TEST_CASE("trained models know their symmetry and mirror symmetry", "[vision][model]") {
  const std::map<std::string, double> symmetry = {
      {"rectangle", 180}, {"l_shape", 360},    {"gear", 30},     {"hex_nut", 60},
      {"triangle", 120},  {"disc_holes", 360}, {"t_shape", 360}, {"slot", 360}};
  const std::map<std::string, bool> mirror = {
      {"rectangle", true}, {"l_shape", false},    {"gear", true},    {"hex_nut", true},
      {"triangle", true},  {"disc_holes", false}, {"t_shape", true}, {"slot", true}};
  int id = 1;
  for (const auto& [type, deg] : symmetry) {
    INFO(type);
    const Trained t = train(type, id++);
    CHECK(t.model.symmetryDeg() == deg);
    CHECK(t.model.body.mirror_symmetric == mirror.at(type));
    CHECK(validateModel(t.model));
    CHECK(checkSymmetry(t.model));
  }
  // A plain disc turns into itself at any angle.
  cv::Mat grey(300, 300, CV_8UC1, cv::Scalar(200));
  cv::circle(grey, {150, 150}, 60, cv::Scalar(40), cv::FILLED, cv::LINE_AA);
  const auto disc = trainModel(grey, 9, "disc");
  REQUIRE(disc.ok());
  CHECK(disc.value().symmetryDeg() == 0);
  CHECK(checkSymmetry(disc.value()));
  CHECK(disc.value().orientation_order == 0);
}

TEST_CASE("a hole becomes one arc and a rectangle four lines with convex right-angle corners",
          "[vision][model]") {
  const Trained slot = train("slot", 1);
  REQUIRE(slot.model.loops.size() == 2);
  REQUIRE(slot.model.loops[1].primitives.size() == 1);
  const Primitive& bore = slot.model.loops[1].primitives[0];
  CHECK(bore.kind == PrimitiveKind::kArc);
  CHECK(std::abs(bore.sweep_deg) == 360);
  CHECK(bore.radius ==
        Approx(0.1 * 120 + 0.5).margin(1.0));  // boundary pixel centres, just outside the hole
  // The stadium's ends are arcs too: line-arc and arc-line corners.
  int line_arc = 0;
  for (const auto& c : slot.model.corners)
    line_arc += c.kind == CornerClass::kLineArc || c.kind == CornerClass::kArcLine;
  CHECK(line_arc >= 2);

  cv::Mat grey(300, 300, CV_8UC1, cv::Scalar(200));
  cv::rectangle(grey, cv::Rect(80, 100, 120, 60), cv::Scalar(40), cv::FILLED);
  const auto rect = trainModel(grey, 2, "rect");
  REQUIRE(rect.ok());
  REQUIRE(rect.value().loops.size() == 1);
  int long_lines = 0;
  for (const auto& p : rect.value().loops[0].primitives)
    long_lines += p.kind == PrimitiveKind::kLine && p.length() > 50;
  CHECK(long_lines == 4);
  int right_angles = 0;
  for (const auto& c : rect.value().corners) {
    if (c.kind == CornerClass::kLineLine && c.convex &&
        (c.turn_deg.contains(90) || c.turn_deg.contains(-90))) {
      ++right_angles;
    }
  }
  CHECK(right_angles >= 4);
}

TEST_CASE("the boundary is trusted as far as its edge is as strong as the part's",
          "[vision][model]") {
  // A dark plate with a faint blotch of the surface against its lower side
  // (30 levels under the surface, the plate 160): a threshold that takes
  // the blotch into the part, as a textured belt's does at low contrast.
  cv::Mat grey(300, 300, CV_8UC1, cv::Scalar(200));
  cv::rectangle(grey, cv::Rect(80, 100, 120, 60), cv::Scalar(40), cv::FILLED);
  cv::rectangle(grey, cv::Rect(120, 160, 30, 20), cv::Scalar(170), cv::FILLED);
  cv::GaussianBlur(grey, grey, cv::Size(0, 0), 0.7);
  // Not cut off as a shadow would be (its level is a shadow's): the mask
  // keeps it whole, as the threshold did.
  RegionOptions whole;
  whole.cut_shadows = false;
  const auto regions = findRegions(grey < 185, whole, grey);
  REQUIRE(regions.size() == 1);
  const auto trained = trainModelFromRegion(grey, regions[0], 1, "plate");
  REQUIRE(trained.ok());
  const PartModel& m = trained.value();
  // Weights by where the primitive runs, in image coordinates.
  double plate_min = 1;
  double blotch_max = 0;
  int blotch = 0;
  for (const auto& p : m.loops[0].primitives) {
    const cv::Point2d mid = p.pointAt(0.5) + m.trained_centroid;
    if (p.length() < 8) continue;  // corners' short primitives: too few readings
    if (mid.y > 163) {
      ++blotch;
      blotch_max = std::max(blotch_max, p.weight);
    } else {
      plate_min = std::min(plate_min, p.weight);
    }
  }
  CHECK(blotch >= 2);
  CHECK(blotch_max < 0.5);
  CHECK(plate_min == 1.0);
}

TEST_CASE("a part is never taken for its mirror image", "[vision][model][mirror]") {
  const Trained l = train("l_shape", 1);
  const Trained m = train("l_shape_mirror", 2);
  for (uint64_t seed : {5u, 6u, 7u}) {
    const ps::SceneRenderer s(scene(1280, 960, 12, seed, {"l_shape", "l_shape_mirror"}));
    // With only the L trained, its mirror images are not reported at all.
    const auto only_l = recognizeScene(s, {&l.model});
    // With both trained, each is reported as itself.
    const auto both = recognizeScene(s, {&l.model, &m.model});
    for (const auto& t : s.truth()) {
      INFO(t.type << " at " << t.x << ", " << t.y);
      const Match* a = nearest(only_l, t);
      CHECK((a != nullptr) == (t.type == "l_shape"));
      const Match* b = nearest(both, t);
      REQUIRE(b);
      CHECK(b->model->name == t.type);
    }
  }
}

TEST_CASE("parts of the same shape and another size are told apart by area", "[vision][model]") {
  const Trained big = train("l_shape", 1);
  const Trained small = train("l_shape_small", 2);
  const ps::SceneRenderer s(scene(1280, 960, 10, 9, {"l_shape", "l_shape_small"}));
  const auto matches = recognizeScene(s, {&big.model, &small.model});
  CHECK(matches.size() == 10);
  for (const auto& t : s.truth()) {
    const Match* m = nearest(matches, t);
    REQUIRE(m);
    CHECK(m->model->name == t.type);
  }
}

TEST_CASE("recognized parts: position, and rotation from the trained pose", "[vision][model]") {
  const auto& types = ps::allPartTypes();
  const auto set = picksight::test::trainAll(types, train);
  const auto& trained = set.trained;
  const auto& models = set.models;
  double worst_position = 0;
  double worst_angle = 0;
  for (uint64_t seed : {21u, 22u}) {
    const ps::SceneRenderer s(scene(1920, 1080, 20, seed, types));
    const auto matches = recognizeScene(s, models);
    CHECK(matches.size() == 20);
    // Best first: a robot taking the first part takes the surest one.
    CHECK(std::is_sorted(matches.begin(), matches.end(),
                         [](const Match& a, const Match& b) { return a.score > b.score; }));
    for (const auto& t : s.truth()) {
      INFO(t.type << " at " << t.x << ", " << t.y << " turned " << t.angle_deg);
      const Match* m = nearest(matches, t);
      REQUIRE(m);
      CHECK(m->model->name == t.type);
      CHECK(m->score >= 0.9);
      const double position = std::hypot(m->centroid.x - t.x, m->centroid.y - t.y);
      CHECK(position < 0.1);
      const double angle =
          angleDiffDeg(m->angle_deg, t.angle_deg - trained.at(t.type).truth_angle, m->symmetry_deg);
      CHECK(angle < 0.3);
      // The turn nearest the taught pose (reportedTurnDeg).
      if (m->symmetry_deg > 0) {
        CHECK(m->angle_deg > -m->symmetry_deg / 2);
        CHECK(m->angle_deg <= m->symmetry_deg / 2);
      } else {
        CHECK(m->angle_deg == 0);
      }
      worst_position = std::max(worst_position, position);
      worst_angle = std::max(worst_angle, angle);
    }
  }
  WARN("worst position error " << worst_position << " px, worst rotation error " << worst_angle
                               << " deg");
}

namespace {
// `loops` contours of `points` boundary pixels each, scattered over `box`
// and `margin` pixels past each of its sides (some near its edges, some
// outside it).
std::vector<std::vector<cv::Point>> scatteredContours(uint64_t seed, int loops, int points,
                                                      const cv::Rect& box, int margin) {
  cv::RNG rng(seed);
  std::vector<std::vector<cv::Point>> contours(static_cast<size_t>(loops));
  for (auto& c : contours) {
    for (int i = 0; i < points; ++i) {
      c.emplace_back(rng.uniform(box.x - margin, box.br().x + margin),
                     rng.uniform(box.y - margin, box.br().y + margin));
    }
  }
  return contours;
}
}  // namespace

TEST_CASE("the bounded edge map has the exact distances within its reach", "[vision][model]") {
  // Boundary pixels anywhere, some near the box's edges and some outside it,
  // against the distance to the nearest of them, pixel by pixel.
  const cv::Rect box(0, 0, 60, 40);
  const auto contours = scatteredContours(11, 3, 40, box, 6);
  const double reach = 4.3;
  const EdgeDistance bounded(contours, box, reach);
  int within = 0;
  for (int y = 0; y < box.height; ++y) {
    for (int x = 0; x < box.width; ++x) {
      double nearest = 1e9;
      for (const auto& c : contours) {
        for (const auto& q : c) nearest = std::min(nearest, std::hypot(q.x - x, q.y - y));
      }
      const cv::Point2d p(x, y);
      INFO(x << ", " << y << ": nearest " << nearest << ", map " << bounded.at(p));
      if (nearest <= reach) {
        CHECK(std::abs(bounded.at(p) - nearest) < 1e-5);
        ++within;
      } else {
        CHECK(bounded.at(p) > reach);
      }
    }
  }
  CHECK(within > box.area() / 4);
}

TEST_CASE("the edge map's test of a tolerance answers as its distances do", "[vision][model]") {
  // A map with a reach holds whole squared distances and tests a tolerance
  // against them; it must answer at(p) <= tolerance exactly, also where the
  // tolerance is a distance the map holds (2, the root of 5, of 13) or just
  // either side of one, and outside the map. Likewise on an exact map.
  const cv::Rect box(0, 0, 50, 30);
  const auto contours = scatteredContours(23, 2, 30, box, 4);
  cv::RNG rng(29);
  const EdgeDistance bounded(contours, box, 6.5);
  const EdgeDistance exact(contours, box);
  const double root5 = std::sqrt(5.0);
  const double root13 = static_cast<double>(std::sqrt(13.0f));
  for (const double tolerance :
       {0.0, 0.5, 1.0, 2.0, std::nextafter(2.0, 0.0), std::nextafter(2.0, 3.0), root5,
        std::nextafter(root5, 0.0), root13, std::nextafter(root13, 0.0), 3.0, 6.0, 6.5, 7.0}) {
    for (const EdgeDistance* map : {&bounded, &exact}) {
      const EdgeDistance::Within within = map->withinOf(tolerance);
      int agreed = 0;
      for (int i = 0; i < 3000; ++i) {
        // Pixel centres and points between them, some outside the box.
        const cv::Point2d p = i % 2 == 0
                                  ? cv::Point2d(rng.uniform(-3, 53), rng.uniform(-3, 33))
                                  : cv::Point2d(rng.uniform(-3.0, 53.0), rng.uniform(-3.0, 33.0));
        INFO("tolerance " << tolerance << " at " << p << ": distance " << map->at(p));
        CHECK(map->isWithin(p, within) == (map->at(p) <= tolerance));
        agreed += map->at(p) <= tolerance ? 1 : 0;
      }
      if (tolerance >= 2.0) CHECK(agreed > 100);  // the test saw points within
    }
  }
}

TEST_CASE("verification fails when the model is off the part", "[vision][model]") {
  const Trained l = train("l_shape", 1);
  const ps::SceneRenderer s(scene(400, 400, 1, 78, {"l_shape"}));
  const cv::Mat grey = s.render(0);
  const auto regions = findRegions(binarize(grey, {}), {}, grey);
  REQUIRE(regions.size() == 1);
  std::vector<std::vector<cv::Point>> contours{regions[0].outer};
  const EdgeDistance edges(contours, cv::Rect(0, 0, 400, 400));
  const cv::Point2d c = regions[0].centroid;
  CHECK(verifyScore(l.model.samples, c, 0, edges, l.model.edge_tolerance) > 0.95);
  CHECK(verifyScore(l.model.samples, c + cv::Point2d(6, 0), 0, edges, l.model.edge_tolerance) <
        0.6);
  CHECK(verifyScore(l.model.samples, c, 0, edges, l.model.edge_tolerance, true) < 0.8);
}

TEST_CASE("a boundary's distance is its nearest primitive's, of lines and arcs alike",
          "[vision][model]") {
  // The distance skips primitives whose box lies farther than the nearest
  // found so far: it must still be the least over every primitive, for
  // points on, inside, outside and far from trained boundaries (a gear's
  // arcs, an L's lines, a disc's holes).
  std::vector<BoundaryLoop> loops;
  for (const auto& [type, id] :
       std::vector<std::pair<std::string, int>>{{"gear", 1}, {"l_shape", 2}, {"disc_holes", 3}}) {
    const Trained t = train(type, id);
    loops.insert(loops.end(), t.model.loops.begin(), t.model.loops.end());
  }
  // Arcs whose bulge lies beyond their ends, so that a box of the ends
  // alone would be wrong.
  size_t arcs = 0;
  for (const auto& loop : loops)
    for (const auto& p : loop.primitives) arcs += p.kind == PrimitiveKind::kArc ? 1 : 0;
  REQUIRE(arcs >= 3);
  cv::RNG rng(3);
  for (int i = 0; i < 4000; ++i) {
    // Half near a boundary point, half anywhere around the parts.
    cv::Point2d p(rng.uniform(-150.0, 150.0), rng.uniform(-150.0, 150.0));
    if (i % 2 == 0) {
      const auto& loop = loops[static_cast<size_t>(rng.uniform(0, static_cast<int>(loops.size())))];
      const auto& prim = loop.primitives[static_cast<size_t>(
          rng.uniform(0, static_cast<int>(loop.primitives.size())))];
      p = prim.pointAt(rng.uniform(0.0, 1.0)) +
          cv::Point2d(rng.uniform(-6.0, 6.0), rng.uniform(-6.0, 6.0));
    }
    double every = std::numeric_limits<double>::infinity();
    for (const auto& loop : loops)
      for (const auto& prim : loop.primitives) every = std::min(every, primitiveDistance(prim, p));
    INFO(p.x << ", " << p.y);
    REQUIRE(boundaryDistance(loops, p) == every);
  }
  // Asked in order along the boundary turned and mirrored, as the symmetry
  // and hand tests ask it, from the last point's nearest primitive.
  for (const double turn : {0.0, 37.0, 180.0}) {
    const double c = std::cos(turn * M_PI / 180);
    const double s = std::sin(turn * M_PI / 180);
    PrimitiveIndex nearest;
    for (const auto& sample : sampleBoundary(loops, 1.0)) {
      const cv::Point2d u(c * sample.point.x + s * sample.point.y,
                          s * sample.point.x - c * sample.point.y);
      double every = std::numeric_limits<double>::infinity();
      for (const auto& loop : loops)
        for (const auto& prim : loop.primitives)
          every = std::min(every, primitiveDistance(prim, u));
      INFO(turn << ": " << u.x << ", " << u.y);
      REQUIRE(boundaryDistance(loops, u, &nearest) == every);
    }
  }
}
