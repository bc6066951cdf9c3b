// Parts that touch (one merged blob) against the generator's exact truth:
// every part type in a touching pair, the mirrored pair, the sub-pixel edge
// fit on its own, and where it puts public silhouettes.
#include <catch2/catch.hpp>

#include "recognition_support.hpp"

#include <map>

#include "picksight/codecs/codecs.hpp"

#include "picksight/common/angles.hpp"
#include "picksight/synthetic/scene.hpp"
#include "picksight/synthetic/silhouette_scene.hpp"
#include "picksight/vision/blob_search/touching_parts.hpp"
#include "picksight/vision/recognition/region_judge.hpp"

using namespace picksight::vision;
namespace ps = picksight::synthetic;
using picksight::angleDiffDeg;

namespace {
ps::SceneOptions scene(int parts, uint64_t seed, std::vector<std::string> types, bool touching) {
  ps::SceneOptions o = ps::sceneOptions(640, 480, parts, seed, std::move(types));
  o.blur_sigma = 0.7;
  o.touching = touching;
  return o;
}

using picksight::test::nearest;
using picksight::test::Trained;

Trained train(const std::string& type, int id) {
  return picksight::test::trainOn(scene(1, 300 + static_cast<uint64_t>(id), {type}, false), id,
                                  type);
}

std::vector<Match> recognizeScene(const ps::SceneRenderer& s,
                                  const std::vector<const PartModel*>& models) {
  return picksight::test::recognizeFrame(s, 3, models);
}

// A scene whose two parts touch (the generator may fail to bring a pair into
// contact from a seed: the next seed is tried).
ps::SceneRenderer touchingPair(std::vector<std::string> types, uint64_t seed) {
  for (uint64_t s = seed;; ++s) {
    ps::SceneRenderer r(scene(2, s, types, true));
    if (r.truth()[0].touching) return r;
  }
}
}  // namespace

TEST_CASE("touching parts of every type are found inside their merged blob", "[vision][locator]") {
  const auto& types = ps::allPartTypes();
  const auto set = picksight::test::trainAll(types, train);
  const auto& trained = set.trained;
  const auto& models = set.models;
  uint64_t seed = 40;
  for (const auto& type : types) {
    const ps::SceneRenderer s = touchingPair({type}, seed);
    seed += 10;
    const cv::Mat grey = s.render(3);
    const auto regions = findRegions(binarize(grey, {}), {}, grey);
    // Otherwise the pair would not test the locator at all.
    REQUIRE(regions.size() == 1);
    const auto matches = recognize(regions, models);
    CHECK(matches.size() == 2);
    for (const auto& t : s.truth()) {
      INFO(t.type << " at " << t.x << ", " << t.y << " turned " << t.angle_deg);
      const Match* m = nearest(matches, t);
      REQUIRE(m);
      CHECK(m->model->name == t.type);
      CHECK(m->touching);
      CHECK(m->score * 100 >= m->model->verify_percent);
      CHECK(std::hypot(m->centroid.x - t.x, m->centroid.y - t.y) < 0.15);
      CHECK(angleDiffDeg(m->angle_deg, t.angle_deg - trained.at(t.type).truth_angle,
                         m->symmetry_deg) < 0.2);
    }
  }
}

TEST_CASE("a touching part is never taken for its mirror image", "[vision][locator][mirror]") {
  const Trained l = train("l_shape", 1);
  const Trained m = train("l_shape_mirror", 2);
  for (uint64_t seed : {11u, 31u, 51u}) {
    const ps::SceneRenderer s = touchingPair({"l_shape", "l_shape_mirror"}, seed);
    const auto only_l = recognizeScene(s, {&l.model});
    const auto both = recognizeScene(s, {&l.model, &m.model});
    for (const auto& t : s.truth()) {
      INFO(t.type << " at " << t.x << ", " << t.y << " (seed " << seed << ")");
      const Match* a = nearest(only_l, t);
      CHECK((a != nullptr) == (t.type == "l_shape"));
      const Match* b = nearest(both, t);
      REQUIRE(b);
      CHECK(b->model->name == t.type);
    }
    for (const auto& match : only_l) CHECK(match.model->name == "l_shape");
  }
}

TEST_CASE("the edge fit moves a pose a few pixels off onto the part", "[vision][locator]") {
  const Trained t = train("l_shape", 1);
  const ps::SceneRenderer s(scene(1, 9, {"l_shape"}, false));
  const cv::Mat grey = s.render(0);
  const auto regions = findRegions(binarize(grey, {}), {}, grey);
  REQUIRE(regions.size() == 1);
  const ps::PartTruth& truth = s.truth()[0];
  const double angle = truth.angle_deg - t.truth_angle;
  const ImagePose start{{truth.x + 1.5, truth.y - 1.0}, angle + 2.0, false};
  const EdgeFit fit = refinePoseOnEdges(t.model, regions[0], start);
  REQUIRE(fit.ok);
  CHECK(std::hypot(fit.pose.centre.x - truth.x, fit.pose.centre.y - truth.y) < 0.05);
  CHECK(angleDiffDeg(fit.pose.angle_deg, angle) < 0.05);
  CHECK(fit.inlier_fraction > 0.95);
  CHECK(fit.rms_px < 0.2);
}

TEST_CASE("a part located from its edges lands on its drawn centroid", "[vision][locator]") {
  // The bell and the bone: their boundaries, as the snap to the edges left
  // them, put parts located from their edges 0.25 and 0.13 px off.
  struct Spec {
    const char* name;
    const char* file;
    double size_px;
  };
  const Spec specs[] = {{"bell", "shapes/tari1000/obj41_1.png", 190},
                        {"bone", "shapes/kimia99/trainimage9_1.png", 240}};
  BinarizeOptions binarize_options;
  binarize_options.adaptive_window = 400;  // wider than any part, as the bench sets it
  TrainOptions train_options;
  train_options.binarize = binarize_options;
  const ps::SilhouetteSceneOptions look;
  std::vector<ps::SilhouetteType> types;
  std::vector<PartModel> models;
  for (size_t i = 0; i < std::size(specs); ++i) {
    const std::string path = std::string(PICKSIGHT_TEST_DATA_DIR) + "/" + specs[i].file;
    const cv::Mat drawing = picksight::codecs::imread(path, cv::IMREAD_GRAYSCALE);
    INFO(path);
    REQUIRE_FALSE(drawing.empty());
    types.push_back(ps::silhouetteFromDrawing(specs[i].name, drawing, specs[i].size_px));
    const int side = static_cast<int>(specs[i].size_px * 1.5) + 300;
    const cv::Mat image = ps::renderSilhouetteAlone(types.back(), side, look, 7 + i, nullptr);
    auto outcome = trainModel(image, static_cast<int>(i), specs[i].name, train_options);
    REQUIRE(outcome.ok());
    models.push_back(outcome.value());
  }
  const std::vector<const PartModel*> list{&models[0], &models[1]};

  ps::SilhouetteSceneOptions o = look;
  o.width = 1280;
  o.height = 720;
  o.parts = 8;
  o.seed = 5;
  o.distractor_share = 0;
  const ps::SilhouetteScene scene(types, std::vector<bool>(types.size(), true), o);
  const cv::Mat grey = scene.render(0);
  const auto regions = findRegions(binarize(grey, binarize_options), {}, grey);
  int located = 0;
  for (const auto& t : scene.truth()) {
    // Each part alone in its blob, located the way a touching part is.
    size_t index = regions.size();
    for (size_t i = 0; i < regions.size(); ++i) {
      if (cv::norm(regions[i].centroid - t.centre) < 12) index = i;
    }
    INFO(specs[t.type].name << " at " << t.centre.x << ", " << t.centre.y << " turned "
                            << t.angle_deg);
    REQUIRE(index < regions.size());
    const auto matches = locateInBlob(regions, index, list);
    REQUIRE(matches.size() == 1);
    CHECK(static_cast<size_t>(matches[0].model->type) == t.type);
    CHECK(cv::norm(matches[0].centroid - t.centre) < 0.1);
    // Searched on the edge map the region tests build (wider reach and
    // box), the same part at the same pose to the last bit.
    RegionCache cache(regions[index],
                      std::max(models[0].edge_tolerance, models[1].edge_tolerance) + 0.5);
    const auto shared = locateInBlob(regions, index, list, &cache.edges());
    REQUIRE(shared.size() == 1);
    CHECK(shared[0].model == matches[0].model);
    CHECK(shared[0].centroid == matches[0].centroid);
    CHECK(shared[0].angle_deg == matches[0].angle_deg);
    ++located;
  }
  CHECK(located >= 6);
}
