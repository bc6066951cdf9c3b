// Teaching and locating under a front-lit cell's light, as a user does it:
// LEARN on a textured belt takes the one part a person sees and names the
// specks it left out; LOCATE's smallest region follows the taught parts; a
// green part on a grey belt of the same brightness is taught and found in
// colour; a model's colour survives its file; the sweets photograph; a part
// taught beside its shadow is found beside shadows falling elsewhere.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>
#include "picksight/codecs/codecs.hpp"

#include "picksight/app/offline_commands.hpp"
#include "picksight/cell/vision_service.hpp"
#include "picksight/common/angles.hpp"
#include "picksight/common/atomic_file.hpp"
#include "picksight/common/frame.hpp"
#include "picksight/store/model_file.hpp"
#include "picksight/synthetic/front_light.hpp"
#include "picksight/synthetic/silhouette_scene.hpp"
#include "picksight/vision/recognition/recognition_pass.hpp"
#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/vision/segmentation/regions.hpp"
#include "picksight/vision/training/part_training.hpp"

using namespace picksight;
using namespace picksight::cell;
using namespace picksight::store;
namespace ps = picksight::synthetic;
namespace pv = picksight::vision;

namespace {
// A look of the named condition (front_light.hpp).
ps::SilhouetteSceneOptions lookOf(const std::string& condition) {
  ps::SilhouetteSceneOptions look;
  REQUIRE(
      ps::frontLightCondition(condition, &look.front, &look.part_level, &look.background_level));
  return look;
}

VisionOptions cellOptions() {
  VisionOptions o;
  o.binarize.adaptive_window = 400;
  return o;
}

std::shared_ptr<const ModelList> noModels() { return std::make_shared<const ModelList>(); }

std::shared_ptr<const ModelList> listOf(const pv::PartModel& m) {
  return std::make_shared<const ModelList>(ModelList{m});
}

// The box a user drags around a part drawn at `centre`, `size` across.
cv::Rect boxAround(cv::Point2d centre, double size) {
  const double half = 0.6 * size;
  return {static_cast<int>(centre.x - half), static_cast<int>(centre.y - half),
          static_cast<int>(2 * half), static_cast<int>(2 * half)};
}

// Parts of `truth` of kind kTrue found by `parts` within 2 px.
int foundTrue(const std::vector<ps::SilhouettePart>& truth, const std::vector<LocatedPart>& parts) {
  int found = 0;
  for (const auto& t : truth) {
    if (t.kind != ps::PartKind::kTrue) continue;
    for (const auto& p : parts) {
      if (p.type >= 0 && std::hypot(p.x - t.centre.x, p.y - t.centre.y) < 2) {
        ++found;
        break;
      }
    }
  }
  return found;
}

const ps::SilhouetteType& boneType() {
  static const ps::SilhouetteType t = ps::silhouetteFromPartType("t_shape", 200);
  return t;
}

// Six parts of `type`, separated, no distractors, under `look`.
ps::SilhouetteScene sixParts(const ps::SilhouetteType& type, ps::SilhouetteSceneOptions look,
                             cv::Size size, uint64_t seed) {
  look.width = size.width;
  look.height = size.height;
  look.parts = 6;
  look.distractor_share = 0;
  look.seed = seed;
  return ps::SilhouetteScene({type}, {true}, look);
}

// A public silhouette of this repository's test data, `size` px across.
ps::SilhouetteType drawing(const std::string& file, double size) {
  const cv::Mat image = picksight::codecs::imread(std::string(PICKSIGHT_TEST_DATA_DIR) + "/" + file,
                                                  cv::IMREAD_GRAYSCALE);
  REQUIRE(!image.empty());
  return ps::silhouetteFromDrawing(file, image, size);
}

// Four parts of `types` under `look` in a 1000 x 800 frame, touching or
// overlapping by pairs, no distractors.
ps::SilhouetteScene fourByPairs(const std::vector<ps::SilhouetteType>& types,
                                ps::SilhouetteSceneOptions look, ps::Arrangement arrangement,
                                uint64_t seed) {
  look.width = 1000;
  look.height = 800;
  look.parts = 4;
  look.distractor_share = 0;
  look.arrangement = arrangement;
  look.seed = seed;
  return ps::SilhouetteScene(types, std::vector<bool>(types.size(), true), look);
}

// Each of `types` taught alone under `look` with LEARN ... AT a box
// `box_px` across, as types 1, 2, ...
std::shared_ptr<ModelList> teachEach(const std::vector<ps::SilhouetteType>& types,
                                     const ps::SilhouetteSceneOptions& look, double box_px) {
  auto models = std::make_shared<ModelList>();
  for (const auto& type : types) {
    cv::Point2d at;
    const cv::Mat teach = ps::renderSilhouetteAlone(type, 645, look, 7, &at, 30);
    auto learned =
        learnInImage(teach, {}, cellOptions(), models, static_cast<int>(models->size()) + 1,
                     type.name, boxAround(at, box_px));
    INFO(type.name << ": " << (learned.ok() ? std::string() : learned.error().message));
    REQUIRE(learned.ok());
    models->push_back(learned->model);
  }
  return models;
}

// LOCATE ALL on `scene` with `models` (teachEach's types): `found(truth,
// part)` for each part drawn that is reported as its type within 2 px.
// Returns the number of parts drawn.
template <class F>
int forEachFound(const ps::SilhouetteScene& scene, const std::shared_ptr<ModelList>& models,
                 F&& found) {
  const Frame frame = frameFromImage(scene.render(0), "cam0", 1);
  const LocateOutcome outcome = locateInFrame(frame, cellOptions(), models, -1);
  for (const auto& t : scene.truth()) {
    for (const auto& p : outcome.parts) {
      if (p.type == static_cast<int>(t.type) + 1 &&
          std::hypot(p.x - t.centre.x, p.y - t.centre.y) <= 2)
        found(t, p);
    }
  }
  return static_cast<int>(scene.truth().size());
}
}  // namespace

// A model file is refused, naming what is wrong, when the first list under
// `key` in `yaml` is replaced by each of `lists` (with the words each
// refusal must hold), and when that list's first value is replaced by
// `beyond` (the count right, the value out of bounds: `beyond_why`).
void checkDamagedListsRefused(const std::string& yaml, const std::string& key,
                              const std::vector<std::pair<std::string, std::string>>& lists,
                              const std::string& beyond, const std::string& beyond_why) {
  const std::string opening = key + ": [";
  const auto at = yaml.find(opening);
  REQUIRE(at != std::string::npos);
  for (const auto& [list, why] : lists) {
    std::string damaged = yaml;
    damaged.replace(at, damaged.find(']', at) + 1 - at, key + ": " + list);
    const auto refused = modelFromYaml(damaged);
    INFO(key << ": " << list);
    REQUIRE_FALSE(refused.ok());
    CHECK(refused.error().message.find(why) != std::string::npos);
  }
  std::string damaged = yaml;
  const auto first = at + opening.size();
  damaged.replace(first, damaged.find_first_of(",]", first) - first, beyond);
  const auto refused = modelFromYaml(damaged);
  INFO(key << ": first value " << beyond);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message.find(beyond_why) != std::string::npos);
}

// A worn belt: the textured condition with twice its grain and blotches, so
// that its darkest spots binarize as specks and stains beside the parts.
ps::SilhouetteSceneOptions wornBelt() {
  ps::SilhouetteSceneOptions look = lookOf("textured");
  look.front.texture = 0.12;
  return look;
}

// The t-shaped part alone on the textured belt, with a dozen specks of dirt
// (discs 11 to 13 px across at the part's level) around it, away from it: what
// the belt's grain gives depends on the last bits of the texture's filters,
// these do not.
cv::Mat partAmongSpecks(cv::Point2d* drawn) {
  cv::Mat image = ps::renderSilhouetteAlone(boneType(), 600, lookOf("textured"), 11, drawn, 30);
  for (int k = 0; k < 12; ++k) {
    const double a = 2 * M_PI * k / 12;
    const cv::Point at(static_cast<int>(300 + 250 * std::cos(a)),
                       static_cast<int>(300 + 250 * std::sin(a)));
    cv::circle(image, at, 5 + k % 2, cv::Scalar(45), cv::FILLED, cv::LINE_AA);
  }
  return image;
}

TEST_CASE("LEARN on a textured belt takes the part and names the specks it left out",
          "[vision_app][learn][front]") {
  cv::Point2d drawn;
  const cv::Mat image = partAmongSpecks(&drawn);
  // The specks are regions as LOCATE sees them with no model.
  const auto regions = pv::findRegions(pv::binarize(image, cellOptions().binarize), {}, image);
  REQUIRE(regions.size() >= 13);
  const auto learned = learnInImage(image, {}, cellOptions(), noModels(), 1, "tee", std::nullopt);
  INFO((learned.ok() ? std::string() : learned.error().message));
  REQUIRE(learned.ok());
  CHECK(std::abs(learned->model.trained_centroid.x - drawn.x) < 1);
  CHECK(std::abs(learned->model.trained_centroid.y - drawn.y) < 1);
  REQUIRE(learned->notes.size() == 1);
  CHECK(learned->notes.front().find("specks") != std::string::npos);
  // LEARN ... AT a box around it says the same.
  const auto at =
      learnInImage(image, {}, cellOptions(), noModels(), 1, "tee", boxAround(drawn, 200));
  REQUIRE(at.ok());
  CHECK(at->model.body.area == Approx(learned->model.body.area).epsilon(1e-9));
  // A stain of a tenth of the part's area (a worn belt's, at the part's
  // level) is still a stain beside it, not a second part.
  cv::Mat stained = image.clone();
  const double radius = std::sqrt(0.10 * learned->model.body.area / M_PI);
  cv::circle(stained, cv::Point(75, 75), static_cast<int>(std::lround(radius)), cv::Scalar(45),
             cv::FILLED, cv::LINE_AA);
  const auto with_stain =
      learnInImage(stained, {}, cellOptions(), noModels(), 1, "tee", std::nullopt);
  INFO((with_stain.ok() ? std::string() : with_stain.error().message));
  REQUIRE(with_stain.ok());
  CHECK(with_stain->model.body.area == Approx(learned->model.body.area).epsilon(0.01));
}

TEST_CASE("LEARN on wood takes the part, not the grain's stripes", "[vision_app][learn][front]") {
  // Wood's rings are sharp steps too, but they fall dark again a few pixels
  // on: they must not set the threshold, or the grain splits into stripes
  // as large as the part.
  for (const uint64_t seed : {11U, 12U, 13U}) {
    CAPTURE(seed);
    cv::Point2d drawn;
    const cv::Mat image =
        ps::renderSilhouetteAlone(boneType(), 600, lookOf("wood"), seed, &drawn, 30);
    const auto learned = learnInImage(image, {}, cellOptions(), noModels(), 1, "tee", std::nullopt);
    INFO((learned.ok() ? std::string() : learned.error().message));
    REQUIRE(learned.ok());
    CHECK(std::abs(learned->model.trained_centroid.x - drawn.x) < 1);
    CHECK(std::abs(learned->model.trained_centroid.y - drawn.y) < 1);
  }
}

TEST_CASE("LEARN still refuses two parts on a textured belt", "[vision_app][learn][front]") {
  ps::SilhouetteSceneOptions o = wornBelt();
  o.width = 800;
  o.height = 600;
  o.parts = 2;
  o.distractor_share = 0;
  const ps::SilhouetteScene scene({boneType()}, {true}, o);
  REQUIRE(scene.truth().size() == 2);
  const auto learned =
      learnInImage(scene.render(0), {}, cellOptions(), noModels(), 1, "tee", std::nullopt);
  REQUIRE_FALSE(learned.ok());
  CHECK(learned.error().code == pv::PartModelErrc::kSeveralParts);
}

TEST_CASE("LOCATE's smallest region follows the taught parts unless the user set one",
          "[vision_app][locate][front]") {
  cv::Point2d drawn;
  const cv::Mat image = partAmongSpecks(&drawn);
  const auto learned =
      learnInImage(image, {}, cellOptions(), noModels(), 1, "tee", boxAround(drawn, 200));
  REQUIRE(learned.ok());
  const Frame frame = frameFromImage(image, "cam0", 1);
  const auto models = listOf(learned->model);
  const LocateOutcome followed = locateInFrame(frame, cellOptions(), models, -1);
  VisionOptions fixed = cellOptions();
  fixed.min_area_follows_models = false;
  const LocateOutcome set = locateInFrame(frame, fixed, models, -1);
  // The part is found either way; the twelve specks (and the belt's own) are regions only when
  // the user asked for regions that small.
  for (const auto* outcome : {&followed, &set}) {
    REQUIRE(outcome->parts.size() == 1);
    CHECK(outcome->parts.front().type == 1);
    CHECK(std::hypot(outcome->parts.front().x - drawn.x, outcome->parts.front().y - drawn.y) < 1);
  }
  CHECK(followed.scene.regions.size() == 1);
  CHECK(set.scene.regions.size() >= 13);  // and any speck of the belt itself
  CHECK(vision::speckAreaFor(*models) == Approx(0.05 * learned->model.body.area));
}

TEST_CASE("a green part on a grey belt of the same brightness is taught and found in colour",
          "[vision_app][colour][front]") {
  ps::SilhouetteSceneOptions o = lookOf("colour");
  cv::Point2d drawn;
  const cv::Mat alone = ps::renderSilhouetteAlone(boneType(), 600, o, 13, &drawn, 30);
  REQUIRE(alone.type() == CV_8UC3);
  const auto learned =
      learnInImage(alone, {}, cellOptions(), noModels(), 1, "tee", boxAround(drawn, 200));
  REQUIRE(learned.ok());
  REQUIRE(learned->model.colour.has_value());
  CHECK(cv::norm(learned->model.trained_centroid - drawn) < 0.5);
  // In grey the part is the belt's level: what LEARN finds there (a blotch
  // of the belt, if anything) is not the part.
  cv::Mat grey;
  cv::cvtColor(alone, grey, cv::COLOR_BGR2GRAY);
  const auto in_grey =
      learnInImage(grey, {}, cellOptions(), noModels(), 1, "tee", boxAround(drawn, 200));
  if (in_grey.ok()) {
    CHECK(std::abs(in_grey->model.body.area / learned->model.body.area - 1) > 0.2);
  }
  CHECK(cv::norm(learned->model.colour->part - cv::Vec3d(60, 160, 70)) < 40);
  o.width = 1280;
  o.height = 960;
  o.parts = 8;
  o.distractor_share = 0;
  const ps::SilhouetteScene scene({boneType()}, {true}, o);
  const Frame frame = frameFromImage(scene.render(0), "cam0", 1);
  const LocateOutcome located = locateInFrame(frame, cellOptions(), listOf(learned->model), -1);
  CHECK(foundTrue(scene.truth(), located.parts) == static_cast<int>(scene.truth().size()));
}

TEST_CASE("a green part on a grey belt is taught from a colour image file without a rectangle",
          "[vision_app][colour][front][offline]") {
  // A camera's colour image saved to a file is read in colour by the offline
  // commands, as the live frame is (they read every file in grey, where this
  // part is the belt's level). Over the whole frame, the surface's colour
  // read on its rim (darkened by the vignette) set the frame's lit middle
  // apart, not the part: the part is told by its hue.
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("picksight-offline-colour-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  ps::SilhouetteSceneOptions o = lookOf("colour");
  const cv::Mat alone = ps::renderSilhouetteAlone(boneType(), 630, o, 13, nullptr, 30);
  REQUIRE(picksight::codecs::imwrite((dir / "part.png").string(), alone));
  o.width = 1280;
  o.height = 960;
  o.parts = 8;
  o.distractor_share = 0;
  const ps::SilhouetteScene scene({boneType()}, {true}, o);
  REQUIRE(picksight::codecs::imwrite((dir / "scene.png").string(), scene.render(0)));
  const auto run = [&](const std::string& command, const std::string& image) {
    std::vector<std::string> args{command, "--data-dir", (dir / "data").string(), "--window",
                                  "400"};
    if (command == "learn") args.insert(args.end(), {"--type", "1", "--name", "tee"});
    args.push_back((dir / image).string());
    std::ostringstream out, err;
    const int status = app::runOfflineCommand(args, out, err);
    INFO(err.str());
    CHECK(status == 0);
    return out.str();
  };
  const std::string taught = run("learn", "part.png");
  CHECK_THAT(taught, Catch::StartsWith("OK 1 tee "));
  CHECK_THAT(taught, !Catch::Contains("came compressed"));
  const std::string located = run("locate", "scene.png");
  CHECK_THAT(located, Catch::StartsWith("OK " + std::to_string(scene.truth().size()) + " "));
  // The same image as a JPEG (a phone's, an IP camera's): taught in colour
  // still, with the warning that its colour came at half resolution.
  REQUIRE(picksight::codecs::imwrite((dir / "part.jpg").string(), alone,
                                     {cv::IMWRITE_JPEG_QUALITY, 90}));
  const std::string from_jpeg = run("learn", "part.jpg");
  CHECK_THAT(from_jpeg, Catch::StartsWith("OK 1 tee "));
  CHECK_THAT(from_jpeg, Catch::Contains("came compressed"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("a model's colour survives its file, and a damaged colour is refused",
          "[vision_app][colour][front]") {
  ps::SilhouetteSceneOptions o = lookOf("colour");
  cv::Point2d drawn;
  const cv::Mat alone = ps::renderSilhouetteAlone(boneType(), 600, o, 13, &drawn, 30);
  const auto learned =
      learnInImage(alone, {}, cellOptions(), noModels(), 1, "tee", boxAround(drawn, 200));
  REQUIRE(learned.ok());
  REQUIRE(learned->model.colour.has_value());
  const std::string yaml = modelToYaml(learned->model);
  const auto back = modelFromYaml(yaml);
  REQUIRE(back.ok());
  REQUIRE(back->colour.has_value());
  CHECK(back->colour->part == learned->model.colour->part);
  CHECK(back->colour->background == learned->model.colour->background);
  std::string damaged = yaml;
  const auto at = damaged.find("part_bgr: [");
  REQUIRE(at != std::string::npos);
  damaged.replace(at, 11, "part_bgr: [900, ");
  CHECK_FALSE(modelFromYaml(damaged).ok());
}

TEST_CASE("a model's edge offsets survive its file and a resize, and damaged ones are refused",
          "[vision_app][learn][front]") {
  cv::Point2d drawn;
  const cv::Mat alone = ps::renderSilhouetteAlone(boneType(), 600, lookOf("textured"), 13, &drawn);
  const auto learned =
      learnInImage(alone, {}, cellOptions(), noModels(), 1, "tee", boxAround(drawn, 200));
  REQUIRE(learned.ok());
  const pv::PartModel& m = learned->model;
  REQUIRE(m.symmetry_order == 1);
  // Read on the teach image: one a pixel, not all on the lines and arcs.
  int offsets = 0;
  int off_primitive = 0;
  for (const auto& loop : m.loops) {
    for (const auto& p : loop.primitives) {
      CHECK(static_cast<int>(p.edge_offsets_mpx.size()) == pv::edgeOffsetCount(p.length()));
      for (const int16_t v : p.edge_offsets_mpx) off_primitive += std::abs(v) >= 50 ? 1 : 0;
      offsets += static_cast<int>(p.edge_offsets_mpx.size());
    }
  }
  CAPTURE(offsets, off_primitive);
  CHECK(off_primitive > 0);
  const std::string yaml = modelToYaml(m);
  const auto back = modelFromYaml(yaml);
  REQUIRE(back.ok());
  REQUIRE(back->loops.size() == m.loops.size());
  for (size_t l = 0; l < m.loops.size(); ++l) {
    REQUIRE(back->loops[l].primitives.size() == m.loops[l].primitives.size());
    for (size_t k = 0; k < m.loops[l].primitives.size(); ++k) {
      CHECK(back->loops[l].primitives[k].edge_offsets_mpx ==
            m.loops[l].primitives[k].edge_offsets_mpx);
    }
  }
  // A camera resized to half: half as many offsets, each half as far as
  // the taught ones at its place along the primitive.
  const pv::PartModel half = pv::scaledModel(m, 0.5);
  CHECK(pv::validateModel(half).ok());
  int moved = 0;
  for (size_t l = 0; l < m.loops.size(); ++l) {
    for (size_t k = 0; k < m.loops[l].primitives.size(); ++k) {
      const pv::Primitive& p = m.loops[l].primitives[k];
      const pv::Primitive& q = half.loops[l].primitives[k];
      const int count = pv::edgeOffsetCount(q.length());
      REQUIRE(static_cast<int>(q.edge_offsets_mpx.size()) == count);
      for (int i = 0; i < count; ++i) {
        const double taught = p.edgeOffsetAt((i + 0.5) / count);
        CHECK(std::abs(0.001 * q.edge_offsets_mpx[static_cast<size_t>(i)] - 0.5 * taught) <= 0.001);
        moved += std::abs(taught) >= 0.01 ? 1 : 0;
      }
    }
  }
  CHECK(moved > 0);
  // Damaged: refused, naming what is wrong, never read as no offsets (one
  // offset beyond the bound, the count right, too).
  checkDamagedListsRefused(yaml, "edge_offsets_mpx",
                           {{"[1, 2]", "edge offsets (one a pixel)"},
                            {"7", "'edge_offsets_mpx' must be a list"},
                            {"[1.5, 2]", "whole number"}},
                           "9999", "within 3.0 px");
}

TEST_CASE("the sweets photograph: a green sweet taught in colour is found",
          "[vision_app][photograph][colour][front]") {
  const cv::Mat photo = picksight::codecs::imread(
      std::string(PICKSIGHT_TEST_DATA_DIR) + "/scenes/smarties.png", cv::IMREAD_COLOR);
  REQUIRE(!photo.empty());
  VisionOptions options;
  // The green sweet alone in the upper middle, as a user drags the box.
  const cv::Rect box(236, 85, 64, 64);
  const auto learned = learnInImage(photo, {}, options, noModels(), 1, "green", box);
  REQUIRE(learned.ok());
  REQUIRE(learned->model.colour.has_value());
  // Green: its green level well above its blue and red ones.
  const cv::Vec3d green = learned->model.colour->part;
  CHECK(green[1] > green[0] + 40);
  CHECK(green[1] > green[2] + 40);
  const Frame frame = frameFromImage(photo, "cam0", 1);
  const LocateOutcome located = locateInFrame(frame, options, listOf(learned->model), -1);
  const cv::Point2d taught = learned->model.trained_centroid;
  bool found = false;
  for (const auto& p : located.parts) {
    found = found || (p.type == 1 && std::hypot(p.x - taught.x, p.y - taught.y) < 1);
  }
  CHECK(found);
}

namespace {
// The warnings LEARN gives the t-shaped part alone under `condition`.
std::vector<std::string> learnWarningsUnder(const std::string& condition) {
  cv::Point2d drawn;
  const cv::Mat image =
      ps::renderSilhouetteAlone(boneType(), 600, lookOf(condition), 12, &drawn, 30);
  const auto learned =
      learnInImage(image, {}, cellOptions(), noModels(), 1, "tee", boxAround(drawn, 200));
  REQUIRE(learned.ok());
  for (const auto& w : learned->warnings) UNSCOPED_INFO(condition << ": " << w);
  return learned->warnings;
}

bool mentions(const std::vector<std::string>& warnings, const std::string& word) {
  for (const auto& w : warnings) {
    if (w.find(word) != std::string::npos) return true;
  }
  return false;
}
}  // namespace

TEST_CASE("LEARN warns of the shadows and reflections it sees and of nothing else",
          "[vision_app][learn][front]") {
  const auto clean = learnWarningsUnder("clean");
  const auto textured = learnWarningsUnder("textured");
  const auto shadow = learnWarningsUnder("shadow");
  const auto glossy = learnWarningsUnder("glossy");
  CHECK(clean.empty());
  CHECK(textured.empty());
  CHECK(mentions(shadow, "shadow"));
  CHECK_FALSE(mentions(shadow, "reflection"));
  CHECK(mentions(glossy, "reflection"));
  CHECK_FALSE(mentions(glossy, "shadow"));
}

TEST_CASE("a part taught beside its shadow is found and placed beside shadows falling elsewhere",
          "[vision_app][locate][front]") {
  // The shadow condition: a textured belt, a soft shadow 8 px long. Taught
  // at 30 degrees, the part's shadow lies along other edges of it at every
  // other angle of the scene; left joined, it changes the region's shape.
  const ps::SilhouetteSceneOptions look = lookOf("shadow");
  cv::Point2d drawn;
  const cv::Mat teach = ps::renderSilhouetteAlone(boneType(), 600, look, 11, &drawn, 30);
  const ps::SilhouetteScene scene = sixParts(boneType(), look, {1000, 800}, 3);
  REQUIRE(scene.truth().size() == 6);
  const Frame frame = frameFromImage(scene.render(0), "cam0", 1);
  int found_cut = 0;
  int found_joined = 0;
  for (const bool cut : {true, false}) {
    VisionOptions options = cellOptions();
    options.regions.cut_shadows = cut;
    const auto learned = learnInImage(teach, {}, options, noModels(), 1, "tee", std::nullopt);
    INFO((learned.ok() ? std::string() : learned.error().message));
    REQUIRE(learned.ok());
    const LocateOutcome outcome = locateInFrame(frame, options, listOf(learned->model), -1);
    (cut ? found_cut : found_joined) = foundTrue(scene.truth(), outcome.parts);
    if (!cut) continue;
    // Each within a pixel of the drawn part (its shadow left out).
    for (const auto& p : outcome.parts) {
      double nearest = 1e9;
      for (const auto& t : scene.truth()) {
        nearest = std::min(nearest, std::hypot(p.x - t.centre.x, p.y - t.centre.y));
      }
      CHECK(nearest < 1.0);
    }
  }
  CHECK(found_cut == 6);
  // Left joined, the shadows cost parts: the scene tests the cut.
  CHECK(found_joined < 6);
}

TEST_CASE("the turn of a separated part under a front light is read on its edges",
          "[vision_app][locate][front][accuracy]") {
  // Glints, a lit side within a few levels of the belt, a grained belt:
  // the moments' phase and the distance map's descent weigh the rim's
  // uneven coverage and turned such parts by a tenth of a degree or more.
  // Public silhouettes (Tari-1000) of classes and drawings the front-light
  // benchmark does not use, each taught alone and found among six.
  std::vector<ps::SilhouetteType> shapes;
  for (const int k : {2, 4, 7, 9, 12, 14, 17, 19, 21, 24}) {
    const std::string file = "shapes/tari1000/obj" + std::to_string(k) + "_7.png";
    const cv::Mat drawing = picksight::codecs::imread(
        std::string(PICKSIGHT_TEST_DATA_DIR) + "/" + file, cv::IMREAD_GRAYSCALE);
    REQUIRE(!drawing.empty());
    shapes.push_back(ps::silhouetteFromDrawing(file, drawing, 220));
  }
  // Read on the edges: 0.009 to 0.014 degrees RMS; the judge's turn gave
  // 0.065 (glossy), 0.092 (low contrast) and 0.115 (wood). The limit is the
  // goal of a front-lit cell.
  const std::vector<std::pair<const char*, double>> limits = {
      {"glossy", 0.05}, {"low-contrast", 0.05}, {"wood", 0.05}};
  for (const auto& [condition, limit] : limits) {
    double sum2 = 0;
    int found = 0;
    int drawn_parts = 0;
    for (const auto& shape : shapes) {
      CAPTURE(condition, shape.name);
      const ps::SilhouetteSceneOptions look = lookOf(condition);
      cv::Point2d centre;
      const cv::Mat teach = ps::renderSilhouetteAlone(shape, 645, look, 11, &centre, 30);
      const auto learned =
          learnInImage(teach, {}, cellOptions(), noModels(), 1, "part", boxAround(centre, 280));
      INFO((learned.ok() ? std::string() : learned.error().message));
      REQUIRE(learned.ok());
      const ps::SilhouetteScene scene = sixParts(shape, look, {1200, 900}, 5);
      const Frame frame = frameFromImage(scene.render(0), "cam0", 1);
      const LocateOutcome outcome = locateInFrame(frame, cellOptions(), listOf(learned->model), -1);
      for (const auto& t : scene.truth()) {
        ++drawn_parts;
        for (const auto& p : outcome.parts) {
          if (p.type != 1 || std::hypot(p.x - t.centre.x, p.y - t.centre.y) > 2) continue;
          const double e = angleDiffDeg(p.angle_deg, t.angle_deg - 30, p.symmetry_deg);
          sum2 += e * e;
          ++found;
        }
      }
    }
    CAPTURE(condition, found, drawn_parts);
    CHECK(found >= 0.98 * drawn_parts);
    const double rms = std::sqrt(sum2 / std::max(found, 1));
    CAPTURE(rms);
    CHECK(rms < limit);
  }
}

// Ten t-shaped parts under `look` in a 1280 x 960 frame, separated, no
// distractors.
ps::SilhouetteScene tenTees(ps::SilhouetteSceneOptions look, uint64_t seed) {
  look.width = 1280;
  look.height = 960;
  look.parts = 10;
  look.distractor_share = 0;
  look.seed = seed;
  return ps::SilhouetteScene({boneType()}, {true}, look);
}

TEST_CASE("parts in the corners of a vignetted frame at 30 levels of contrast are found too",
          "[vision_app][locate][front]") {
  // The low-contrast condition loses a quarter of its light in the corners:
  // more than the 30 levels between part and surface, and the corners of
  // its frames still binarize as specks of the surface (the background
  // estimate stands above the surface there). Parts drawn near the frame's
  // edge must be found all the same: a guard for any change to the
  // binarization or the speck handling.
  const ps::SilhouetteSceneOptions look = lookOf("low-contrast");
  cv::Point2d drawn;
  const cv::Mat teach = ps::renderSilhouetteAlone(boneType(), 600, look, 11, &drawn, 30);
  const auto learned =
      learnInImage(teach, {}, cellOptions(), noModels(), 1, "tee", boxAround(drawn, 200));
  INFO((learned.ok() ? std::string() : learned.error().message));
  REQUIRE(learned.ok());
  int outer = 0;
  for (const uint64_t seed : {3, 5, 8}) {
    const ps::SilhouetteScene scene = tenTees(look, seed);
    const Frame frame = frameFromImage(scene.render(0), "cam0", 1);
    const LocateOutcome outcome = locateInFrame(frame, cellOptions(), listOf(learned->model), -1);
    INFO("seed " << seed);
    CHECK(foundTrue(scene.truth(), outcome.parts) == static_cast<int>(scene.truth().size()));
    for (const auto& t : scene.truth()) {
      const double from_edge =
          std::min({t.centre.x, t.centre.y, 1280 - t.centre.x, 960 - t.centre.y});
      outer += from_edge < 220 ? 1 : 0;
    }
  }
  // The scenes put parts where the light has fallen most.
  CHECK(outer >= 6);
}

// The look of a condition on a photographed surface (tests/data/surfaces).
ps::SilhouetteSceneOptions photographedLook(const std::string& condition) {
  const cv::Mat photo = picksight::codecs::imread(
      std::string(PICKSIGHT_TEST_DATA_DIR) + "/surfaces/" + condition + ".png",
      cv::IMREAD_GRAYSCALE);
  REQUIRE(!photo.empty());
  ps::SilhouetteSceneOptions look;
  REQUIRE(ps::photographedCondition(condition, photo, &look.front, &look.part_level,
                                    &look.background_level));
  return look;
}

TEST_CASE("parts on photographed paving bricks and gravel at 30 levels of contrast are found",
          "[vision_app][locate][front]") {
  // Real surfaces (photographs, not drawn here) under the low-contrast
  // light: the light joints between bricks and the light flecks of gravel
  // step up from the surface as sharply as a part's edge steps down. When
  // they set the threshold, each brick darker than the joints beside it
  // became a region, parts beside them were split or joined to them, and
  // on gravel 12 of these 30 parts were found.
  for (const char* condition : {"brick", "gravel"}) {
    const ps::SilhouetteSceneOptions look = photographedLook(condition);
    cv::Point2d drawn;
    const cv::Mat teach = ps::renderSilhouetteAlone(boneType(), 600, look, 11, &drawn, 30);
    const auto learned =
        learnInImage(teach, {}, cellOptions(), noModels(), 1, "tee", boxAround(drawn, 200));
    INFO(condition << ": " << (learned.ok() ? std::string() : learned.error().message));
    REQUIRE(learned.ok());
    int truth = 0;
    int found = 0;
    for (const uint64_t seed : {3, 5, 8}) {
      const ps::SilhouetteScene scene = tenTees(look, seed);
      const Frame frame = frameFromImage(scene.render(0), "cam0", 1);
      const LocateOutcome outcome = locateInFrame(frame, cellOptions(), listOf(learned->model), -1);
      truth += static_cast<int>(scene.truth().size());
      const int right = foundTrue(scene.truth(), outcome.parts);
      found += right;
      // Nothing else: no brick or stone taken for a part.
      CHECK(outcome.parts.size() == static_cast<size_t>(right));
    }
    // One part on gravel lies in the corner where the light has fallen
    // most: the gaps between the stones there are as dark as the part, and
    // join it to the frame's edge.
    CHECK(found >= truth - 1);
  }
}

TEST_CASE("LEARN AT takes a small part on paving bricks, not the darker bricks beside it",
          "[vision_app][learn][front]") {
  // At 30 grey levels on photographed paving bricks, bricks darker than
  // their neighbours binarize as regions of half a small part's area,
  // speckled, and ringed by light joints: read against the joints' mean
  // they stood off the surface half as deep as the part, and LEARN AT
  // around the part (Tari-1000 obj18 at 190 px) counted them as parts.
  const cv::Mat drawing = picksight::codecs::imread(
      std::string(PICKSIGHT_TEST_DATA_DIR) + "/shapes/tari1000/obj18_3.png", cv::IMREAD_GRAYSCALE);
  REQUIRE(!drawing.empty());
  const ps::SilhouetteType type = ps::silhouetteFromDrawing("obj18", drawing, 190);
  const ps::SilhouetteSceneOptions look = photographedLook("brick");
  cv::Point2d drawn;
  const cv::Mat teach = ps::renderSilhouetteAlone(type, 585, look, 15, &drawn, 30);
  const cv::Rect box = boxAround(drawn, 190);
  const auto learned = learnInImage(teach, {}, cellOptions(), noModels(), 1, "obj18", box);
  INFO((learned.ok() ? std::string() : learned.error().message));
  REQUIRE(learned.ok());
  CHECK(cv::norm(learned->model.trained_centroid - drawn) < 1);
  // The darker bricks are regions beside the part in LEARN's first reading
  // (else this tests nothing), where they must not count as parts; its
  // second, at the part's own level, leaves them surface.
  pv::BinarizeOptions first;
  first.adaptive_window = cellOptions().binarize.adaptive_window;
  int bricks = 0;
  for (const auto& r : pv::findRegions(pv::binarize(teach, first), {}, teach)) {
    const bool inside = (r.bbox & box).area() >= 0.5 * r.bbox.area();
    if (inside && !r.bbox.contains(drawn) && r.area > 0.15 * learned->model.body.area) ++bricks;
  }
  CHECK(bricks >= 1);
}

TEST_CASE("LEARN refuses a patch of the surface's own light, and says so",
          "[vision_app][learn][front]") {
  // A belt with one dark stain and no part: the stain's rim is nowhere a
  // step in grey level, however dark its middle. Taught, it would match
  // stains and tell a robot to pick them.
  cv::Mat belt(600, 600, CV_32F);
  cv::Mat noise(belt.size(), CV_32F);
  cv::RNG rng(7);
  rng.fill(noise, cv::RNG::NORMAL, 0, 3);
  for (int y = 0; y < belt.rows; ++y) {
    for (int x = 0; x < belt.cols; ++x) {
      const double r2 = (x - 300.0) * (x - 300.0) + (y - 300.0) * (y - 300.0);
      belt.at<float>(y, x) = static_cast<float>(150 - 45 * std::exp(-r2 / (2 * 70.0 * 70.0)));
    }
  }
  cv::Mat image;
  cv::Mat(belt + noise).convertTo(image, CV_8U);
  // The stain is one region to the threshold: what LEARN would have taken.
  const auto regions = pv::findRegions(pv::binarize(image, cellOptions().binarize), {}, image);
  REQUIRE(!regions.empty());
  CHECK(regions.front().area > 5000);
  CHECK(!pv::outlineSteps(regions.front()));
  const auto learned = learnInImage(image, {}, cellOptions(), noModels(), 1, "stain", std::nullopt);
  REQUIRE(!learned.ok());
  CHECK(learned.error().code == pv::PartModelErrc::kNoPart);
  CHECK_THAT(learned.error().message, Catch::Contains("no edge along its outline"));
  // A grey camera is not told to read a colour.
  CHECK(learned.error().message.find("colour") == std::string::npos);
  const auto at =
      learnInImage(image, {}, cellOptions(), noModels(), 1, "stain", cv::Rect(150, 150, 300, 300));
  REQUIRE(!at.ok());
  CHECK_THAT(at.error().message, Catch::Contains("no edge along its outline"));
  // A part on the same belt is still taught.
  cv::Mat with_part = image.clone();
  cv::circle(with_part, {300, 300}, 60, cv::Scalar(60), cv::FILLED, cv::LINE_AA);
  const auto part = learnInImage(with_part, {}, cellOptions(), noModels(), 1, "disc", std::nullopt);
  INFO((part.ok() ? std::string() : part.error().message));
  CHECK(part.ok());
}

TEST_CASE("touching parts whose corners the light blurs are found from what their blob leaves",
          "[vision_app][locate][front][accuracy]") {
  // Public silhouettes (Tari-1000) the blob search was not written on,
  // touching and overlapping by pairs, on a textured belt and on wood. There
  // a noisy outline's corners open tens of degrees away from the model's, and
  // no pose was proposed for one part in 30 to 50; what the parts found leave
  // is that part, less what they hide of it. Found of the 96 parts of each
  // arrangement: touching, 93 before the search of what is left; overlapping,
  // 93 with that search at the middle alone (an overlapped part's middle
  // lies 5 to 11 px from its reference point); 96 and 96 now (95 overlapping
  // in the scenes as a clang build renders them). Asked: the recall
  // goal, 0.98, and nothing falsely reported.
  const std::vector<std::pair<std::string, ps::SilhouetteType>> shapes = {
      {"obj8", drawing("shapes/tari1000/obj8_3.png", 230)},
      {"obj5", drawing("shapes/tari1000/obj5_3.png", 240)},
      {"obj18", drawing("shapes/tari1000/obj18_3.png", 190)},
      {"obj1", drawing("shapes/tari1000/obj1_3.png", 220)}};
  // Found and reported of the parts drawn, touching and overlapping.
  struct Count {
    int truths = 0;
    int found = 0;
    int reported = 0;
  };
  Count counts[2];
  for (const char* condition : {"textured", "wood"}) {
    const ps::SilhouetteSceneOptions look = lookOf(condition);
    // Each type taught as a user does: LEARN ... AT a box around it, alone
    // under the same light.
    auto models = std::make_shared<ModelList>();
    std::vector<ps::SilhouetteType> types;
    for (const auto& shape : shapes) {
      cv::Point2d at;
      const cv::Mat teach = ps::renderSilhouetteAlone(shape.second, 645, look, 7, &at, 30);
      auto learned =
          learnInImage(teach, {}, cellOptions(), models, static_cast<int>(models->size()) + 1,
                       shape.first, boxAround(at, 240));
      INFO(condition << " " << shape.first << ": "
                     << (learned.ok() ? std::string() : learned.error().message));
      REQUIRE(learned.ok());
      models->push_back(learned->model);
      types.push_back(shape.second);
    }
    for (const bool overlapping : {false, true}) {
      Count& count = counts[overlapping ? 1 : 0];
      for (uint64_t seed = 1; seed <= 12; ++seed) {
        const ps::SilhouetteScene scene = fourByPairs(
            types, look, overlapping ? ps::Arrangement::kOverlapping : ps::Arrangement::kTouching,
            seed);
        const Frame frame = frameFromImage(scene.render(0), "cam0", 1);
        const LocateOutcome outcome = locateInFrame(frame, cellOptions(), models, -1);
        count.truths += static_cast<int>(scene.truth().size());
        count.found += foundTrue(scene.truth(), outcome.parts);
        for (const auto& p : outcome.parts) count.reported += p.type >= 0 ? 1 : 0;
      }
    }
  }
  for (const bool overlapping : {false, true}) {
    const Count& count = counts[overlapping ? 1 : 0];
    INFO((overlapping ? "overlapping" : "touching") << ": " << count.found << " of " << count.truths
                                                    << " found, " << count.reported << " reported");
    CHECK(count.found >= 0.98 * count.truths);
    CHECK(count.reported == count.found);
  }
}

TEST_CASE("parts taught alone on gravel keep their own outline and are found touching",
          "[vision_app][learn][locate][front][sweep]") {
  // A part alone in a whole frame of photographed gravel: the frame is
  // surface but for a hundredth of it, and its levels are no two
  // populations. Otsu split the stones' own shades, the contrast came out
  // a third of the part's, every stone's edge set the threshold near it,
  // and the part's outline took in the crevices beside it (bumps of up to
  // 8 px, the whole outline half a pixel out). Such models screened
  // touching parts at 0.64 where models taught on card gave 0.91, and in
  // a scene of the front-light benchmark's gravel 7 of 18 touching parts
  // were found.
  // LEARN reads the frame again at the part's own level against the
  // surface's.
  ps::SilhouetteSceneOptions look = photographedLook("gravel");
  const std::vector<std::pair<std::string, ps::SilhouetteType>> shapes = {
      {"obj8", drawing("shapes/tari1000/obj8_3.png", 230)},
      {"obj5", drawing("shapes/tari1000/obj5_3.png", 240)},
      {"obj18", drawing("shapes/tari1000/obj18_3.png", 190)},
      {"obj1", drawing("shapes/tari1000/obj1_3.png", 220)}};
  const VisionOptions defaults;
  auto models = std::make_shared<ModelList>();
  std::vector<ps::SilhouetteType> types;
  for (const auto& [name, type] : shapes) {
    cv::Point2d drawn;
    const cv::Mat teach = ps::renderSilhouetteInFrame(type, look, 7, {900.3, 520.6}, &drawn, 30);
    auto learned = learnInImage(teach, {}, defaults, models, static_cast<int>(models->size()) + 1,
                                name, std::nullopt);
    INFO(name << ": " << (learned.ok() ? std::string() : learned.error().message));
    REQUIRE(learned.ok());
    models->push_back(learned->model);
    types.push_back(type);
  }
  int truths = 0;
  int found = 0;
  int reported = 0;
  double squared = 0;
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    const ps::SilhouetteScene scene = fourByPairs(types, look, ps::Arrangement::kTouching, seed);
    const LocateOutcome outcome =
        locateInFrame(frameFromImage(scene.render(0), "cam0", 1), defaults, models, -1);
    truths += static_cast<int>(scene.truth().size());
    found += foundTrue(scene.truth(), outcome.parts);
    for (const auto& p : outcome.parts) reported += p.type >= 0 ? 1 : 0;
    for (const auto& t : scene.truth()) {
      for (const auto& p : outcome.parts) {
        const double off = std::hypot(p.x - t.centre.x, p.y - t.centre.y);
        if (p.type == static_cast<int>(t.type) + 1 && off <= 2) squared += off * off;
      }
    }
  }
  const double rms = found > 0 ? std::sqrt(squared / found) : 0;
  INFO(found << " of " << truths << " found, " << reported << " reported, " << rms << " px RMS");
  // 23 of 24 here, 18 before.
  CHECK(found >= 0.95 * truths);
  CHECK(reported == found);
  // Read at the mean level of a part shaded lighter at one end, that end
  // fell to the surface, and the models' origins came out 1.1 to 1.4 px
  // off (all 24 found, 0.99 px RMS); 0.16 px at the level of its faintest
  // stretch (0.18 px before, of 18).
  CHECK(rms < 0.3);
}

namespace {
// A part of Tari-1000 (its 3rd drawing, `size_px` across) alone on
// photographed gravel, where the front-light benchmark teaches the k-th of
// its types (a spot and a seed drawn from k).
cv::Mat onGravelAsTaught(const std::string& name, int size_px, uint64_t k,
                         ps::SilhouetteType* type) {
  const ps::SilhouetteSceneOptions look = photographedLook("gravel");
  *type = drawing("shapes/tari1000/" + name + "_3.png", size_px);
  std::mt19937_64 rng(0x7465616368ULL + 131 * k);
  const double margin = 0.75 * size_px + 20;
  std::uniform_real_distribution<double> x(margin, look.width - 1 - margin);
  std::uniform_real_distribution<double> y(margin, look.height - 1 - margin);
  const double at_x = x(rng);
  const cv::Point2d spot(at_x, y(rng));
  cv::Point2d drawn;
  return ps::renderSilhouetteInFrame(*type, look, 7 + k, spot, &drawn, 30);
}
}  // namespace

TEST_CASE("stones a part's teach outline took in do not keep it from being found touching",
          "[vision_app][learn][locate][front][sweep]") {
  // On photographed gravel a dark stone against the part joins it in the
  // teach image's mask: a bump of a few pixels on the outline, a stretch
  // too short for its primitive's median contrast to see. In a scene the
  // bumps lie on the background, 3 to 5 % of the boundary, and the blob
  // search took the part, touching another, for a look-alike crossing the
  // background (front-light benchmark, gravel, touching: 0.826 of the
  // parts found). The teach image's contrast along the outline weighs them
  // at the least a stretch may weigh. Two of the benchmark's types, taught
  // as it teaches them (the two it missed most), and two it does not have.
  struct Shape {
    std::string name;
    int size_px;
    uint64_t k;
  };
  const std::vector<Shape> shapes = {
      {"obj13", 220, 6}, {"obj3", 200, 1}, {"obj9", 230, 20}, {"obj20", 210, 21}};
  const VisionOptions defaults;
  auto models = std::make_shared<ModelList>();
  std::vector<ps::SilhouetteType> types;
  int weak_points = 0;
  int points = 0;
  for (const auto& [name, size_px, k] : shapes) {
    ps::SilhouetteType type;
    const cv::Mat teach = onGravelAsTaught(name, size_px, k, &type);
    auto learned = learnInImage(teach, {}, defaults, models, static_cast<int>(models->size()) + 1,
                                name, std::nullopt);
    INFO(name << ": " << (learned.ok() ? std::string() : learned.error().message));
    REQUIRE(learned.ok());
    for (const auto& loop : learned->model.loops) {
      for (const auto& p : loop.primitives) {
        points += pv::edgeOffsetCount(p.length());
        for (const uint8_t w : p.edge_weights_pct) weak_points += w < 100 ? 1 : 0;
      }
    }
    models->push_back(learned->model);
    types.push_back(type);
  }
  // Stretches, not whole sides.
  CAPTURE(weak_points, points);
  CHECK(weak_points > 0);
  CHECK(weak_points < 0.2 * points);
  const ps::SilhouetteSceneOptions look = photographedLook("gravel");
  int truths = 0;
  int found = 0;
  int reported = 0;
  for (const auto arrangement : {ps::Arrangement::kTouching, ps::Arrangement::kOverlapping}) {
    for (uint64_t seed = 1; seed <= 6; ++seed) {
      const ps::SilhouetteScene scene = fourByPairs(types, look, arrangement, seed);
      const LocateOutcome outcome =
          locateInFrame(frameFromImage(scene.render(0), "cam0", 1), defaults, models, -1);
      truths += static_cast<int>(scene.truth().size());
      found += foundTrue(scene.truth(), outcome.parts);
      for (const auto& p : outcome.parts) reported += p.type >= 0 ? 1 : 0;
    }
  }
  INFO(found << " of " << truths << " found, " << reported << " reported");
  // 47 of 48 here (46 built by clang: a part on the verge, refined a hair
  // otherwise), 31 with every stretch at its primitive's weight.
  CHECK(found >= truths - 3);
  CHECK(reported == found);
}

TEST_CASE("a model's edge weights survive its file and a resize, and damaged ones are refused",
          "[vision_app][learn][front]") {
  ps::SilhouetteType type;
  const cv::Mat teach = onGravelAsTaught("obj13", 220, 6, &type);
  const auto learned = learnInImage(teach, {}, cellOptions(), noModels(), 1, "obj13", std::nullopt);
  REQUIRE(learned.ok());
  const pv::PartModel& m = learned->model;
  int weighed = 0;
  int in_part = 0;  // primitives part of whose points are a stretch
  for (const auto& loop : m.loops) {
    for (const auto& p : loop.primitives) {
      if (p.edge_weights_pct.empty()) continue;
      ++weighed;
      CHECK(static_cast<int>(p.edge_weights_pct.size()) == pv::edgeOffsetCount(p.length()));
      // A stretch at the least weight, the rest of the primitive at its own.
      for (const int w : p.edge_weights_pct) {
        if (w < 100) CHECK(p.weight * 0.01 * w == Approx(0.1).margin(0.006));
      }
      in_part += *std::max_element(p.edge_weights_pct.begin(), p.edge_weights_pct.end()) == 100;
    }
  }
  REQUIRE(weighed > 0);
  CHECK(in_part > 0);
  const std::string yaml = modelToYaml(m);
  const auto back = modelFromYaml(yaml);
  REQUIRE(back.ok());
  REQUIRE(back->samples.size() == m.samples.size());
  for (size_t i = 0; i < m.samples.size(); ++i)
    CHECK(back->samples[i].weight == Approx(m.samples[i].weight).epsilon(1e-9));
  // A camera resized to half: the same stretches, at half as many points.
  const pv::PartModel half = pv::scaledModel(m, 0.5);
  CHECK(pv::validateModel(half).ok());
  for (size_t l = 0; l < m.loops.size(); ++l) {
    for (size_t k = 0; k < m.loops[l].primitives.size(); ++k) {
      const pv::Primitive& p = m.loops[l].primitives[k];
      const pv::Primitive& q = half.loops[l].primitives[k];
      CHECK(q.edge_weights_pct.empty() == p.edge_weights_pct.empty());
      for (const double t : {0.1, 0.3, 0.5, 0.7, 0.9}) {
        // The weight of a taught point within two (a resized point spans
        // two taught ones) of the same place along the primitive.
        const double dt = 1.0 / std::max(1.0, p.length());
        bool near = false;
        for (int d = -2; d <= 2; ++d) near = near || q.weightAt(t) == p.weightAt(t + d * dt);
        CHECK(near);
      }
    }
  }
  // Damaged: refused, naming what is wrong, never read as full weight (one
  // weight over 100, the count right, too).
  checkDamagedListsRefused(yaml, "edge_weights_pct",
                           {{"[100, 10]", "edge weights (one a pixel)"},
                            {"7", "'edge_weights_pct' must be a list"},
                            {"[1.5, 2]", "whole percent"},
                            {"[-1]", "whole percent"}},
                           "101", "whole percent, 0 to 100");
}

TEST_CASE("a part another lies on is placed by what shows of its edges as a whole one is",
          "[vision_app][locate][front][accuracy]") {
  // Lines and arcs follow a drawn outline only within the conformity; fitted
  // to the edges of a whole part the departures balance, but where another
  // part hides a fifth of its outline those left pull it by tenths of a
  // pixel (the front-light benchmark's overlapping pairs, clean: 0.045 px
  // RMS about each type's own offset, where separated parts scatter by
  // 0.005). Fitted to where the teach image's edges lay, 0.008. Public
  // silhouettes (Tari-1000) of drawings no other test or benchmark uses,
  // each taught alone, then overlapping by pairs; the scatter is read as
  // the benchmark reads it, about each type's mean error on the part.
  std::vector<ps::SilhouetteType> types;
  for (const auto& [k, size] : std::vector<std::pair<int, double>>{
           {9, 220}, {12, 230}, {14, 210}, {19, 240}, {21, 220}, {24, 230}}) {
    types.push_back(drawing("shapes/tari1000/obj" + std::to_string(k) + "_12.png", size));
  }
  const ps::SilhouetteSceneOptions look = lookOf("clean");
  const auto models = teachEach(types, look, 260);
  for (const auto& m : *models) REQUIRE(m.symmetry_order == 1);
  // Per type: the errors on the part of every overlapped part found.
  std::vector<std::vector<cv::Point2d>> errors(types.size());
  int truths = 0;
  int hidden = 0;  // of the parts found, those a tenth or more of whose outline is hidden
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    truths += forEachFound(fourByPairs(types, look, ps::Arrangement::kOverlapping, seed), models,
                           [&](const ps::SilhouettePart& t, const LocatedPart& p) {
                             const double a = t.angle_deg * M_PI / 180;
                             const cv::Point2d e(p.x - t.centre.x, p.y - t.centre.y);
                             errors[t.type].emplace_back(e.x * std::cos(a) + e.y * std::sin(a),
                                                         -e.x * std::sin(a) + e.y * std::cos(a));
                             hidden += t.hidden >= 0.1 ? 1 : 0;
                           });
  }
  double sum2 = 0;
  int found = 0;
  for (const auto& e : errors) {
    cv::Point2d mean(0, 0);
    for (const auto& v : e) mean += v / static_cast<double>(e.size());
    for (const auto& v : e) sum2 += (v - mean).dot(v - mean);
    found += static_cast<int>(e.size());
  }
  const double scatter = std::sqrt(sum2 / std::max(found, 1));
  CAPTURE(truths, found, hidden, scatter);
  CHECK(found >= 0.98 * truths);
  CHECK(hidden >= truths / 2);  // the scenes hide what the case is about
  CHECK(scatter < 0.02);
}

TEST_CASE("a part with rotational symmetry is placed at its centre of symmetry",
          "[vision_app][locate][front][accuracy]") {
  // Found at any of its turns, such a part is fitted to the mean of its
  // teach image's edges over them, about its centre of symmetry: it is
  // then placed by its symmetry, not by where one teach image under a
  // front light read its centroid. Four shapes of 2 to 12 turns, taught
  // alone, separated and overlapping by pairs on a textured belt and
  // glossy: RMS against the drawn centre 0.016 px; fitted to the lines and
  // arcs alone, 0.031 (0.023 textured, 0.037 glossy).
  std::vector<ps::SilhouetteType> types;
  for (const auto& [name, size] : std::vector<std::pair<std::string, double>>{
           {"rectangle", 220}, {"hex_nut", 200}, {"gear", 220}, {"triangle", 230}}) {
    types.push_back(ps::silhouetteFromPartType(name, size));
  }
  double sum2 = 0;
  int found = 0;
  int truths = 0;
  for (const char* condition : {"textured", "glossy"}) {
    const ps::SilhouetteSceneOptions look = lookOf(condition);
    const auto models = teachEach(types, look, 260);
    for (const auto& m : *models) REQUIRE(m.symmetry_order >= 2);
    for (const auto arrangement : {ps::Arrangement::kSeparated, ps::Arrangement::kOverlapping}) {
      for (uint64_t seed = 1; seed <= 12; ++seed) {
        truths += forEachFound(fourByPairs(types, look, arrangement, seed), models,
                               [&](const ps::SilhouettePart& t, const LocatedPart& p) {
                                 sum2 +=
                                     std::pow(p.x - t.centre.x, 2) + std::pow(p.y - t.centre.y, 2);
                                 ++found;
                               });
      }
    }
  }
  const double rms = std::sqrt(sum2 / std::max(found, 1));
  CAPTURE(truths, found, rms);
  CHECK(found >= 0.98 * truths);
  CHECK(rms < 0.022);
}

namespace {
// The regions of `image` (dark on light), read with a window wide enough
// for any part here.
std::vector<pv::Region> partRegions(const cv::Mat& image) {
  pv::BinarizeOptions b;
  b.adaptive_window = 400;
  return pv::findRegions(pv::binarize(image, b), {}, image);
}

// The part of `type`, alone and turned by `angle_deg` in a `side` image, as
// a sharp, evenly back-lit image of it shows it: where its centroid truly
// lies, so that a condition's light counts in an error, not in the truth.
pv::Region sharpPart(const ps::SilhouetteType& type, int side, double angle_deg) {
  ps::SilhouetteSceneOptions sharp;
  sharp.noise_sigma = 0;
  sharp.uneven_light = false;
  cv::Point2d unused;
  const cv::Mat image = ps::renderSilhouetteAlone(type, side, sharp, 1, &unused, angle_deg);
  const auto regions = partRegions(image);
  REQUIRE(!regions.empty());
  size_t largest = 0;
  for (size_t k = 1; k < regions.size(); ++k) {
    if (regions[k].area > regions[largest].area) largest = k;
  }
  return regions[largest];
}

cv::Point2d trueCentroid(const ps::SilhouetteType& type, int side, double angle_deg) {
  return sharpPart(type, side, angle_deg).centroid;
}

}  // namespace

TEST_CASE("views of a part lying elsewhere take one teach image's offset out of its origin",
          "[vision_app][learn][views][front][accuracy]") {
  // Drawings no benchmark teaches, on wood and under glints: one teach
  // image's grain or glint puts the model's origin (the centroid it read) a
  // tenth of a pixel off, and every part found afterwards with it.
  const std::vector<std::pair<std::string, double>> files = {
      {"shapes/tari1000/obj4_3.png", 220},  {"shapes/tari1000/obj10_3.png", 210},
      {"shapes/tari1000/obj31_3.png", 230}, {"shapes/tari1000/obj49_3.png", 200},
      {"shapes/tari1000/obj7_3.png", 220},  {"shapes/tari1000/obj41_3.png", 210}};
  constexpr int kSide = 600;
  constexpr int kViews = 8;
  for (const char* condition : {"wood", "glossy", "textured", "metal"}) {
    const ps::SilhouetteSceneOptions look = lookOf(condition);
    double taught2 = 0;  // squared origin errors with the teach image alone
    double viewed2 = 0;  // and with kViews - 1 views added
    double found1 = 0;   // squared errors of a part found with each model
    double found8 = 0;
    int counted = 0;
    int refused = 0;
    for (size_t i = 0; i < files.size(); ++i) {
      const ps::SilhouetteType type = drawing(files[i].first, files[i].second);
      cv::Point2d drawn;
      const cv::Mat teach = ps::renderSilhouetteAlone(type, kSide, look, 40 + i, &drawn, 30);
      auto learned = learnInImage(teach, {}, cellOptions(), noModels(), 1, "part",
                                  boxAround(drawn, files[i].second));
      REQUIRE(learned.ok());
      if (learned->model.symmetry_order != 1) continue;
      const pv::PartModel alone = learned->model;
      pv::PartModel model = alone;
      for (int v = 1; v < kViews; ++v) {
        const cv::Mat view =
            ps::renderSilhouetteAlone(type, kSide, look, 900 + 31 * i + v, &drawn, 30 + 47 * v);
        auto seen = viewInFrame(frameFromImage(view, "cam0", 1), cellOptions(), listOf(model), 1,
                                std::nullopt);
        if (!seen.ok()) {
          // A user lays the part elsewhere and asks again.
          UNSCOPED_INFO(condition << " " << files[i].first << " view " << v
                                  << " refused: " << seen.error().message);
          ++refused;
          continue;
        }
        model = seen->model;
      }
      CHECK(model.views.size() >= kViews - 2);
      // The origin, in the teach image, against where the centroid truly is.
      const cv::Point2d truth = trueCentroid(type, kSide, 30);
      const cv::Point2d e1 = alone.trained_centroid + alone.origin_shift - truth;
      const cv::Point2d e8 = model.trained_centroid + model.origin_shift - truth;
      taught2 += e1.dot(e1);
      viewed2 += e8.dot(e8);
      // And where each model places the part lying once more elsewhere:
      // the boundary moved with the origin, so the part is reported there.
      const cv::Mat again = ps::renderSilhouetteAlone(type, kSide, look, 700 + i, &drawn, 100);
      const cv::Point2d there = trueCentroid(type, kSide, 100);
      for (const pv::PartModel* m : {&alone, static_cast<const pv::PartModel*>(&model)}) {
        const auto parts = locateInImage(again, {}, cellOptions(), {*m}, 1);
        REQUIRE(parts.size() == 1);
        const cv::Point2d e = cv::Point2d(parts[0].x, parts[0].y) - there;
        (m == &alone ? found1 : found8) += e.dot(e);
      }
      ++counted;
    }
    REQUIRE(counted >= 4);
    CHECK(refused <= 1);
    const double rms1 = std::sqrt(taught2 / counted);
    const double rms8 = std::sqrt(viewed2 / counted);
    const double place1 = std::sqrt(found1 / counted);
    const double place8 = std::sqrt(found8 / counted);
    INFO(condition << ": origin RMS " << rms1 << " -> " << rms8 << " px, a part found " << place1
                   << " -> " << place8 << " px");
    // Every condition gains. Under glints part of the offset is the same in
    // every view (the lamp's side) and stays: there the gain is small (0.91
    // of the origin error); elsewhere it is a quarter and more (textured
    // 0.59, wood 0.69, metal 0.71). Since the teach image's origin is where
    // its edges put the centroid (vision::referencePoint) there is less
    // left to take out: parts found gain 0.72 (textured), 0.67 (wood), 0.84
    // (glossy) and 0.94 (metal) where the grey centroid left 0.43-0.79.
    CHECK(rms8 < rms1);
    CHECK(place8 < place1);
    if (std::string(condition) != "glossy") {
      CHECK(rms8 < 0.8 * rms1);
      CHECK(place8 <= 0.05);
    }
  }
}

namespace {
// The largest region of `image` (partRegions) whose box holds `at`.
pv::Region regionAt(const cv::Mat& image, cv::Point2d at) {
  const auto regions = partRegions(image);
  const pv::Region* found = nullptr;
  for (const auto& r : regions) {
    if (cv::Rect2d(r.bbox).contains(at) && (!found || r.area > found->area)) found = &r;
  }
  REQUIRE(found != nullptr);
  return *found;
}
}  // namespace

TEST_CASE("under uneven light a part's origin is where its edges put its centroid",
          "[vision_app][learn][front][accuracy]") {
  // Drawings no benchmark teaches, each taught on a whole frame of the cell
  // lying somewhere in it (the light falls off towards the corners): the
  // grey levels of one teach image's rim, read against a blotched or glinting
  // surface, put its centroid a tenth of a pixel off, and the model's origin
  // with it; the edges much less.
  const std::vector<std::pair<std::string, double>> files = {
      {"shapes/tari1000/obj12_5.png", 220}, {"shapes/tari1000/obj19_5.png", 210},
      {"shapes/tari1000/obj23_5.png", 230}, {"shapes/tari1000/obj28_5.png", 200},
      {"shapes/tari1000/obj36_5.png", 220}, {"shapes/tari1000/obj44_5.png", 210}};
  const std::vector<cv::Point2d> spots = {{330, 210}, {950, 230}, {400, 500},
                                          {880, 510}, {640, 360}, {250, 520}};
  double all_origin2 = 0;
  double all_grey2 = 0;
  for (const char* condition : {"textured", "glossy", "wood", "metal"}) {
    ps::SilhouetteSceneOptions look = lookOf(condition);
    look.width = 1280;
    look.height = 720;
    ps::SilhouetteSceneOptions sharp;
    sharp.width = look.width;
    sharp.height = look.height;
    sharp.noise_sigma = 0;
    sharp.uneven_light = false;
    double origin2 = 0;  // squared errors of the models' origins
    double grey2 = 0;    // and of the centroids of the parts' grey levels
    for (size_t i = 0; i < files.size(); ++i) {
      const ps::SilhouetteType type = drawing(files[i].first, files[i].second);
      cv::Point2d drawn;
      const cv::Mat frame =
          ps::renderSilhouetteInFrame(type, look, 50 + i, spots[i], &drawn, 30 + 40.0 * i);
      auto learned = learnInImage(frame, {}, cellOptions(), noModels(), 1, "part",
                                  boxAround(drawn, files[i].second));
      REQUIRE(learned.ok());
      const cv::Point2d truth =
          regionAt(ps::renderSilhouetteInFrame(type, sharp, 1, spots[i], &drawn, 30 + 40.0 * i),
                   drawn)
              .centroid;
      const cv::Point2d origin = learned->model.trained_centroid - truth;
      const cv::Point2d grey = regionAt(frame, drawn).centroid - truth;
      origin2 += origin.dot(origin);
      grey2 += grey.dot(grey);
    }
    const double origin_rms = std::sqrt(origin2 / static_cast<double>(files.size()));
    const double grey_rms = std::sqrt(grey2 / static_cast<double>(files.size()));
    INFO(condition << ": origin RMS " << origin_rms << " px, grey centroid RMS " << grey_rms);
    // Measured: textured 0.017 against 0.032, glossy 0.035 / 0.066, wood
    // 0.043 / 0.057, brushed metal 0.030 / 0.035.
    CHECK(origin_rms < grey_rms);
    CHECK(origin_rms <= 0.05);
    all_origin2 += origin2;
    all_grey2 += grey2;
  }
  CHECK(std::sqrt(all_origin2) < 0.75 * std::sqrt(all_grey2));
}

TEST_CASE("views move the origin to the median of their readings and survive the model file",
          "[vision_app][learn][views]") {
  cv::Point2d drawn;
  const cv::Mat teach = ps::renderSilhouetteAlone(boneType(), 600, lookOf("clean"), 3, &drawn, 30);
  auto learned = learnInImage(teach, {}, cellOptions(), noModels(), 1, "tee", std::nullopt);
  REQUIRE(learned.ok());
  pv::PartModel m = learned->model;
  REQUIRE(m.symmetry_order == 1);
  const auto placed = [&](const pv::PartModel& model) {
    const auto parts = locateInImage(teach, {}, cellOptions(), {model}, 1);
    REQUIRE(parts.size() == 1);
    return cv::Point2d(parts[0].x, parts[0].y);
  };
  const cv::Point2d before = placed(m);
  // Readings (teach image's frame) with one far off: the median of
  // {0, 0.2, 0.3, 1.5} in x and {0, -0.1, -0.2, 1.2} in y.
  pv::addViewReading(m, {0.2, -0.1});
  pv::addViewReading(m, {0.3, -0.2});
  pv::addViewReading(m, {1.5, 1.2});
  CHECK(m.origin_shift.x == Approx(0.25).margin(1e-12));
  CHECK(m.origin_shift.y == Approx(-0.05).margin(1e-12));
  REQUIRE(pv::validateModel(m).ok());
  // The part is where it was; it is reported at the new origin.
  const cv::Point2d after = placed(m);
  CHECK(cv::norm(after - before - m.origin_shift) < 0.02);
  const std::string yaml = modelToYaml(m);
  const auto back = modelFromYaml(yaml);
  REQUIRE(back.ok());
  REQUIRE(back->views.size() == 3);
  CHECK(back->views[2] == m.views[2]);
  CHECK(back->origin_shift == m.origin_shift);
  CHECK(cv::norm(placed(*back) - after) < 1e-9);
  // A damaged reading or origin is refused, saying what is wrong, never
  // taken as it reads: each line replaced whole.
  const auto replaced = [&](const std::string& key, const std::string& line) {
    std::string damaged = yaml;
    const auto at = damaged.find(key);
    REQUIRE(at != std::string::npos);
    // From the key on: the line keeps its indentation.
    damaged.replace(at, damaged.find('\n', at) - at, line);
    return damaged;
  };
  for (const auto& [damaged, why] : std::vector<std::pair<std::string, std::string>>{
           {replaced("origin_shift:", "origin_shift: [0.3, -0.05]"), "median"},
           {replaced("origin_shift:", "origin_shift: [0.25, -0.05, 1]"), "[x, y]"},
           {replaced("views:", "views:\n    - [9, 9]"), "within 2.0 px"}}) {
    const auto refused = modelFromYaml(damaged);
    INFO(why << " in\n" << damaged.substr(0, 600));
    REQUIRE_FALSE(refused.ok());
    CHECK(refused.error().message.find(why) != std::string::npos);
  }
}

namespace {
// The part's outline on a sharp, evenly lit image of it.
std::vector<cv::Point> sharpOutline(const ps::SilhouetteType& type, int side, double angle_deg) {
  return sharpPart(type, side, angle_deg).outer;
}

// A stretch of surface as dark as the part, speckled with pinholes (dark
// squares of 3 px, 2 px of surface between them), hung below the part's
// lowest point by a neck `neck` px wide and 6 px long.
void hangSpeckledStretch(cv::Mat& image, const std::vector<cv::Point>& outline, int neck,
                         double level) {
  const cv::Point low =
      *std::max_element(outline.begin(), outline.end(),
                        [](const cv::Point& a, const cv::Point& b) { return a.y < b.y; });
  const cv::Scalar dark(level);
  cv::rectangle(image, cv::Rect(low.x - neck / 2, low.y - 2, neck, 8), dark, cv::FILLED);
  const cv::Point top(low.x - 20, low.y + 6);
  for (int y = 0; y < 30; y += 5) {
    for (int x = 0; x < 40; x += 5) {
      cv::rectangle(image, cv::Rect(top.x + x, top.y + y, 3, 3), dark, cv::FILLED);
    }
  }
  // The squares joined along their rows and columns here and there, as the
  // threshold's speckle joins: a mesh with pinholes.
  for (int y = 0; y < 30; y += 5) {
    cv::rectangle(image, cv::Rect(top.x, top.y + y + 1, 38, 1), dark, cv::FILLED);
  }
  for (int x = 0; x < 40; x += 10) {
    cv::rectangle(image, cv::Rect(top.x + x + 1, top.y, 1, 28), dark, cv::FILLED);
  }
}
}  // namespace

TEST_CASE("LEARN leaves out a speckled stretch of the surface hung on the part by a neck",
          "[vision_app][learn][front]") {
  // At 30 grey levels a blotch of the belt as dark as the part joins it by
  // a few specks, full of pinholes: taught with it, the model counted holes
  // no other copy has and turned its moments, and found nothing again.
  const ps::SilhouetteSceneOptions look = lookOf("low-contrast");
  const ps::SilhouetteType& type = boneType();
  constexpr int kSide = 600;
  cv::Point2d drawn;
  cv::Mat teach = ps::renderSilhouetteAlone(type, kSide, look, 11, &drawn, 30);
  const double part_level = cv::mean(teach, pv::binarize(teach, cellOptions().binarize))[0];
  hangSpeckledStretch(teach, sharpOutline(type, kSide, 30), 3, part_level);
  const cv::Rect box = boxAround(drawn, 260);
  const auto learned = learnInImage(teach, {}, cellOptions(), noModels(), 1, "tee", box);
  INFO((learned.ok() ? std::string() : learned.error().message));
  REQUIRE(learned.ok());
  CHECK(learned->model.body.holes == 0);
  const bool said = std::any_of(learned->notes.begin(), learned->notes.end(), [](const auto& n) {
    return n.find("speckled surface") != std::string::npos;
  });
  CHECK(said);
  // The part alone elsewhere, turned: found, where it truly is.
  const cv::Mat view = ps::renderSilhouetteAlone(type, kSide, look, 12, &drawn, 75);
  const auto parts = locateInImage(view, {}, cellOptions(), {learned->model}, 1);
  REQUIRE(parts.size() == 1);
  CHECK(cv::norm(cv::Point2d(parts[0].x, parts[0].y) - trueCentroid(type, kSide, 75)) < 0.3);

  // The same on a belt's own blotch: a drawing no benchmark teaches, at 30
  // grey levels, where the belt's darker stretch joins the part's lowest
  // tip through speckle, pinholes closed against the tip included (found
  // so: the model counted 20 holes and found the part in no other image).
  {
    const ps::SilhouetteType blob = drawing("shapes/tari1000/obj7_3.png", 220);
    cv::Point2d centre;
    const cv::Mat image = ps::renderSilhouetteAlone(blob, kSide, look, 44, &centre, 30);
    const auto taught =
        learnInImage(image, {}, cellOptions(), noModels(), 1, "blob", boxAround(centre, 220));
    INFO((taught.ok() ? std::string() : taught.error().message));
    REQUIRE(taught.ok());
    CHECK(taught->model.body.holes == 0);
    for (const auto& [seed, angle] : {std::pair<uint64_t, double>{932, 77}, {933, 124}}) {
      const cv::Mat other = ps::renderSilhouetteAlone(blob, kSide, look, seed, &centre, angle);
      const auto found = locateInImage(other, {}, cellOptions(), {taught->model}, 1);
      INFO("seed " << seed);
      CHECK(found.size() == 1);
    }
  }

  // Where the speckle ran along the part's edge a pixel off it, the slit
  // between them stays closed once the speckle beyond the neck is cut: the
  // surface, not a hole of the part. A plain bar, the speckle hung below it
  // by a 3 px neck, its top row a pixel below the bar and joined to it at
  // both ends.
  {
    cv::Mat bar(kSide, kSide, CV_8U, cv::Scalar(look.background_level));
    const cv::Scalar dark(part_level);
    const cv::Rect body(200, 220, 200, 110);
    cv::rectangle(bar, body, dark, cv::FILLED);
    const int edge = body.y + body.height;  // first row under the bar
    cv::rectangle(bar, cv::Rect(290, edge + 1, 14, 1), dark, cv::FILLED);  // the row
    cv::rectangle(bar, cv::Rect(290, edge, 1, 1), dark, cv::FILLED);       // its ends
    cv::rectangle(bar, cv::Rect(303, edge, 1, 1), dark, cv::FILLED);
    hangSpeckledStretch(bar, {{296, edge + 1}}, 3, part_level);
    cv::Mat noise(bar.size(), CV_8S);
    cv::randn(noise, 0, 2);
    bar += noise;  // saturating, as a sensor's noise
    cv::GaussianBlur(bar, bar, cv::Size(), 0.7);
    const auto slit =
        learnInImage(bar, {}, cellOptions(), noModels(), 1, "bar", cv::Rect(170, 190, 260, 230));
    INFO((slit.ok() ? std::string() : slit.error().message));
    REQUIRE(slit.ok());
    const bool cut = std::any_of(slit->notes.begin(), slit->notes.end(), [](const auto& n) {
      return n.find("speckled surface") != std::string::npos;
    });
    CHECK(cut);
    CHECK(slit->model.body.holes == 0);
  }

  // A ring on a thin stem is the part's own, its hole too: kept.
  cv::Mat ringed = ps::renderSilhouetteAlone(type, kSide, look, 11, &drawn, 30);
  const auto outline = sharpOutline(type, kSide, 30);
  const cv::Point low =
      *std::max_element(outline.begin(), outline.end(),
                        [](const cv::Point& a, const cv::Point& b) { return a.y < b.y; });
  cv::rectangle(ringed, cv::Rect(low.x - 1, low.y - 2, 3, 10), cv::Scalar(part_level), cv::FILLED);
  cv::circle(ringed, low + cv::Point(0, 21), 14, cv::Scalar(part_level), cv::FILLED, cv::LINE_AA);
  cv::circle(ringed, low + cv::Point(0, 21), 6, cv::Scalar(look.background_level), cv::FILLED,
             cv::LINE_AA);
  const auto kept = learnInImage(ringed, {}, cellOptions(), noModels(), 1, "tee", box);
  INFO((kept.ok() ? std::string() : kept.error().message));
  REQUIRE(kept.ok());
  CHECK(kept->model.body.holes == 1);
  CHECK(kept->model.body.area > learned->model.body.area + 400);
  const bool cut = std::any_of(kept->notes.begin(), kept->notes.end(), [](const auto& n) {
    return n.find("speckled surface") != std::string::npos;
  });
  CHECK_FALSE(cut);
}

TEST_CASE("LEARN leaves out a stretch of the surface lying against a limb, its outline no edge",
          "[vision_app][learn][front]") {
  // Taught in a dim spot at 30 grey levels, a blotch of the belt half as
  // deep as the part lay against a limb along a neck 6 to 10 px across: the
  // model took it in (800 px on 13400), its origin came out 4.5 px off, and
  // touching copies went unfound. A drawing no benchmark teaches, the
  // blotch a smooth dip in the surface's light (noise and all, two thirds
  // as deep as the part) against its leftmost limb.
  const ps::SilhouetteSceneOptions look = lookOf("low-contrast");
  const ps::SilhouetteType type = drawing("shapes/tari1000/obj30_5.png", 220);
  constexpr int kSide = 600;
  constexpr double kAngle = 20;
  const pv::Region truth = sharpPart(type, kSide, kAngle);
  const cv::Point left =
      *std::min_element(truth.outer.begin(), truth.outer.end(),
                        [](const cv::Point& a, const cv::Point& b) { return a.x < b.x; });
  const double contrast = look.background_level - look.part_level;
  const auto withBlotch = [&](uint64_t seed, double depth_share) {
    cv::Point2d drawn;
    cv::Mat image = ps::renderSilhouetteAlone(type, kSide, look, seed, &drawn, kAngle);
    cv::Mat dip = cv::Mat::zeros(image.size(), CV_32F);
    cv::circle(dip, left + cv::Point(-12, -8), 16, cv::Scalar(1.0), cv::FILLED);
    cv::GaussianBlur(dip, dip, cv::Size(), 6);
    double peak = 0;
    cv::minMaxLoc(dip, nullptr, &peak);
    cv::Mat levels;
    image.convertTo(levels, CV_32F);
    levels -= dip * (depth_share * contrast / peak);
    levels.convertTo(image, CV_8U);
    return image;
  };
  const cv::Rect box = boxAround(trueCentroid(type, kSide, kAngle), 240);
  int joined = 0;
  int cut_notes = 0;
  for (const uint64_t seed : {31, 32, 33, 34}) {
    INFO("seed " << seed);
    const cv::Mat image = withBlotch(seed, 0.65);
    // Binarized as LEARN does, the blotch joins the part (in most of the
    // images, else this test tests nothing).
    bool joins = false;
    for (const auto& r : partRegions(image)) {
      joins = joins || (r.bbox.contains(left) && r.area > truth.area + 300);
    }
    joined += joins ? 1 : 0;
    const auto learned = learnInImage(image, {}, cellOptions(), noModels(), 1, "dog", box);
    INFO((learned.ok() ? std::string() : learned.error().message));
    REQUIRE(learned.ok());
    // The part's own area (the grey rim adds some tens of pixels on every
    // teach image), and its origin where its centroid is but for what is
    // left of the blotch at the neck or taken with it off the limb: 0.15
    // to 0.19 px here built by gcc, up to 0.48 by clang (whose binarization
    // of the same image differs by a few pixels: one limb lost 110 px with
    // the blotch); taken in, 6 px.
    CHECK(std::abs(learned->model.body.area - truth.area) < 150);
    CHECK(cv::norm(learned->model.trained_centroid - truth.centroid) < 0.6);
    const bool said = std::any_of(learned->notes.begin(), learned->notes.end(), [](const auto& n) {
      return n.find("its outline no edge") != std::string::npos;
    });
    // Said only where the blotch joined the part. LEARN's second reading,
    // at the part's own level, may leave the blotch surface (seed 34):
    // then nothing was cut, and nothing is said.
    CHECK((joins || !said));
    cut_notes += said ? 1 : 0;
  }
  CHECK(joined >= 2);
  CHECK(cut_notes >= 2);

  // A lobe of the part's own on a neck as wide: solid, and its outline a
  // step all round, kept (and nothing said).
  cv::Point2d drawn;
  cv::Mat lobed = ps::renderSilhouetteAlone(type, kSide, look, 31, &drawn, kAngle);
  const cv::Scalar part(look.part_level);
  cv::rectangle(lobed, cv::Rect(left.x - 12, left.y - 4, 14, 9), part, cv::FILLED);
  cv::circle(lobed, left + cv::Point(-24, 0), 13, part, cv::FILLED, cv::LINE_AA);
  const auto kept = learnInImage(lobed, {}, cellOptions(), noModels(), 1, "dog", box);
  INFO((kept.ok() ? std::string() : kept.error().message));
  REQUIRE(kept.ok());
  CHECK(kept->model.body.area > truth.area + 500);
  const bool cut = std::any_of(kept->notes.begin(), kept->notes.end(), [](const auto& n) {
    return n.find("left out") != std::string::npos;
  });
  CHECK_FALSE(cut);
}

TEST_CASE("LEARN keeps a limb lying over a darker stretch of the surface, its edge a small step",
          "[vision_app][learn][front][accuracy]") {
  // The front-light benchmark's fourth teaching (--teachings 4) of obj27
  // (Tari-1000, a dog) at 30 grey levels: its tail lies over a darker
  // blotch of the belt, so that its edge steps by less than half the
  // part's step along most of the tail's tip. LEARN took the tip for a
  // stretch of the surface on a wide neck and cut it off (222 px): the
  // model's origin came out 2 px off, and every dog found with it.
  const ps::SilhouetteSceneOptions look = lookOf("low-contrast");
  const ps::SilhouetteType dog = drawing("shapes/tari1000/obj27_3.png", 240);
  // The benchmark's spot, seed and turn for it there (the 12th of its types,
  // the fourth teaching, numbered 3 from 0: teachSpot(11, 0), seed 7 + 11 +
  // 3 x 100003, 30 degrees).
  const cv::Point2d spot(235.07962915799556, 640.71077688873959);
  constexpr uint64_t kSeed = 300027;
  cv::Point2d centre;
  const cv::Mat image = ps::renderSilhouetteInFrame(dog, look, kSeed, spot, &centre, 30);
  // Where the part truly lies: a sharp, evenly back-lit image of it.
  ps::SilhouetteSceneOptions sharp_look;
  sharp_look.noise_sigma = 0;
  sharp_look.uneven_light = false;
  const cv::Mat sharp = ps::renderSilhouetteInFrame(dog, sharp_look, kSeed, spot, nullptr, 30);
  const auto seen = partRegions(sharp);
  REQUIRE(!seen.empty());
  const pv::Region truth = *std::max_element(
      seen.begin(), seen.end(), [](const auto& a, const auto& b) { return a.area < b.area; });
  // Taught as the benchmark teaches it: the cell's own settings.
  const auto learned = learnInImage(image, {}, VisionOptions{}, noModels(), 1, "dog", std::nullopt);
  INFO((learned.ok() ? std::string() : learned.error().message));
  REQUIRE(learned.ok());
  CAPTURE(learned->model.body.area, truth.area, learned->model.trained_centroid, truth.centroid);
  std::string notes;
  for (const auto& note : learned->notes) notes += note + "; ";
  CAPTURE(notes);
  CHECK(learned->model.body.area > truth.area - 120);
  CHECK(cv::norm(learned->model.trained_centroid - truth.centroid) < 0.3);
  CHECK_FALSE(std::any_of(learned->notes.begin(), learned->notes.end(), [](const auto& n) {
    return n.find("its outline no edge") != std::string::npos;
  }));
}

TEST_CASE("picksight-vision learnview reads a part again in each image file and stores the views",
          "[vision_app][learn][views][offline]") {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("picksight-offline-views-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const ps::SilhouetteSceneOptions look = lookOf("wood");
  for (int v = 0; v < 3; ++v) {
    const cv::Mat image =
        ps::renderSilhouetteAlone(boneType(), 600, look, 60 + v, nullptr, 30 + 47 * v);
    REQUIRE(
        picksight::codecs::imwrite((dir / ("view" + std::to_string(v) + ".png")).string(), image));
  }
  const auto run = [&](std::vector<std::string> args, int expected_status) {
    args.insert(args.begin() + 1, {"--data-dir", (dir / "data").string(), "--window", "400"});
    std::ostringstream out, err;
    const int status = app::runOfflineCommand(args, out, err);
    INFO(err.str() << out.str());
    CHECK(status == expected_status);
    return out.str();
  };
  const std::string p0 = (dir / "view0.png").string();
  const std::string p1 = (dir / "view1.png").string();
  const std::string p2 = (dir / "view2.png").string();
  // No model yet: refused by the protocol's code.
  CHECK_THAT(run({"learnview", "--type", "1", p1}, 1), Catch::StartsWith("ERROR 32 "));
  CHECK_THAT(run({"learn", "--type", "1", "--name", "tee", p0}, 0), Catch::StartsWith("OK 1 tee "));
  // Each image a view, in order; one unreadable is said and the next read.
  const std::string views =
      run({"learnview", "--type", "1", p1, (dir / "none.png").string(), p2}, 1);
  std::istringstream lines(views);
  std::string line;
  std::vector<std::string> replies;
  while (std::getline(lines, line)) replies.push_back(line);
  REQUIRE(replies.size() == 3);
  CHECK_THAT(replies[0], Catch::StartsWith("OK 1 tee 2 "));
  CHECK_THAT(replies[1], Catch::StartsWith("ERROR 11 "));
  CHECK_THAT(replies[2], Catch::StartsWith("OK 1 tee 3 "));
  const auto stored = readFile((dir / "data" / "models" / "type_1.yaml").string());
  REQUIRE(stored.ok());
  const auto model = modelFromYaml(*stored);
  REQUIRE(model.ok());
  CHECK(model->views.size() == 2);
  // --at around nothing: no part of the type inside.
  CHECK_THAT(run({"learnview", "--type", "1", "--at", "0", "0", "20", "20", p1}, 1),
             Catch::StartsWith("ERROR 35 "));
  std::filesystem::remove_all(dir);
}

TEST_CASE("LEARN takes the part and not a larger speckled blotch of the belt beside it",
          "[vision_app][learn][front]") {
  // Beside a glossy part on its belt, the threshold took in a blotch of the
  // belt whole, speckled, larger than the part: LEARN measured everything
  // against the largest region and called the part a second part. Here a
  // stretch of belt 220 px square, 80 % of its pixels 40 levels darker.
  cv::Point2d drawn;
  cv::Mat image = ps::renderSilhouetteAlone(boneType(), 600, lookOf("textured"), 11, &drawn, 30);
  const auto alone = learnInImage(image, {}, cellOptions(), noModels(), 1, "tee", std::nullopt);
  REQUIRE(alone.ok());
  cv::RNG rng(7);
  for (int y = 370; y < 590; ++y) {
    for (int x = 10; x < 230; ++x) {
      if (rng.uniform(0.0, 1.0) < 0.8)
        image.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(image.at<uint8_t>(y, x) - 40);
    }
  }
  const auto regions = pv::findRegions(pv::binarize(image, cellOptions().binarize), {}, image);
  double largest = 0;
  for (const auto& r : regions) largest = std::max(largest, r.area);
  REQUIRE(largest > 1.2 * alone->model.body.area);  // the blotch, larger than the part
  const auto learned = learnInImage(image, {}, cellOptions(), noModels(), 1, "tee", std::nullopt);
  INFO((learned.ok() ? std::string() : learned.error().message));
  REQUIRE(learned.ok());
  CHECK(learned->model.body.area == Approx(alone->model.body.area).epsilon(0.01));
  CHECK(learned->model.body.holes == 0);
  CHECK(cv::norm(learned->model.trained_centroid - alone->model.trained_centroid) < 0.1);
  const bool said = std::any_of(learned->notes.begin(), learned->notes.end(), [](const auto& n) {
    return n.find("ignored") != std::string::npos;
  });
  CHECK(said);
}

TEST_CASE("LEARN does not pass over a lighter part for a small dark thing beside it",
          "[vision_app][learn][front]") {
  // A faint region is passed over for the part only when the threshold
  // speckled it: a light grey part (60 levels under its belt) beside a
  // black washer a fifth its size is still the part, and the washer a
  // second part, refused; not a washer taught in its place.
  ps::SilhouetteSceneOptions look = lookOf("clean");
  look.part_level = 140;
  cv::Point2d drawn;
  cv::Mat image = ps::renderSilhouetteAlone(boneType(), 600, look, 11, &drawn, 30);
  const auto alone = learnInImage(image, {}, cellOptions(), noModels(), 1, "tee", std::nullopt);
  INFO((alone.ok() ? std::string() : alone.error().message));
  REQUIRE(alone.ok());
  const double radius = std::sqrt(0.2 * alone->model.body.area / M_PI);
  cv::circle(image, cv::Point(90, 90), static_cast<int>(std::lround(radius)), cv::Scalar(10),
             cv::FILLED, cv::LINE_AA);
  const auto learned = learnInImage(image, {}, cellOptions(), noModels(), 1, "tee", std::nullopt);
  REQUIRE_FALSE(learned.ok());
  CHECK(learned.error().code == pv::PartModelErrc::kSeveralParts);
}

TEST_CASE("a separated part beside a shadow that joins it is placed on its edges",
          "[vision_app][locate][front][accuracy]") {
  // A public bottle (Tari-1000) in the middle of a 1920 x 1080 frame under
  // the front-light benchmark's lamp, turned so that its shadow runs along
  // one long side: 2 to 3 px of it stay joined to the part (too thin for a
  // shadow's layer, too dark beside it to be read in the ring), the
  // region's centroid moves 2.1-2.8 px, and the fit on the edges, which
  // lands 0.3-0.4 px from the part and settles there, was refused as too
  // far from it: placed 2.4-2.8 px off (the benchmark's 15 standard types
  // beside shadows, separated: 0.32 px RMS).
  const ps::SilhouetteType type = drawing("shapes/tari1000/obj32_1.png", 230);
  const ps::SilhouetteSceneOptions look = lookOf("shadow");
  const auto models = teachEach({type}, look, 300);
  double worst = 0;
  for (const int turn : {120, 130, 140}) {
    for (const uint64_t seed : {1, 2}) {
      cv::Point2d centre;
      const cv::Mat image =
          ps::renderSilhouetteInFrame(type, look, seed, {951.6, 505.9}, &centre, turn);
      const LocateOutcome outcome =
          locateInFrame(frameFromImage(image, "cam0", 1), cellOptions(), models, -1);
      CAPTURE(turn, seed);
      REQUIRE(outcome.parts.size() == 1);
      const double off = std::hypot(outcome.parts[0].x - centre.x, outcome.parts[0].y - centre.y);
      CHECK(off < 0.5);
      worst = std::max(worst, off);
    }
  }
  WARN("farthest from the drawn part: " << worst << " px");
}

TEST_CASE("a slender part on wood is taught with the app's own settings and found there",
          "[vision_app][learn][front][sweep]") {
  // A public tulip (Tari-1000) on a long thin stem, 260 px long, on wood in
  // a 1920 x 1080 frame, the vision app's default settings. LEARN read it
  // whole with the frame's own window (180 px), then again with one as wide
  // as the part's reach (446 px): over a window that wide the grain's
  // lightest streaks set the surface's level, and a darker streak beside
  // the part joined it; LEARN counted 71 parts in the frame, LEARN AT four
  // in its box (seed 7; the streak lies elsewhere for the others). A part
  // whole in the first reading is taught from it then.
  const ps::SilhouetteType type = drawing("shapes/tari1000/obj16_1.png", 260);
  const ps::SilhouetteSceneOptions look = lookOf("wood");
  const VisionOptions defaults;
  for (const uint64_t seed : {6, 7, 8}) {
    CAPTURE(seed);
    cv::Point2d taught;
    const cv::Mat teach =
        ps::renderSilhouetteInFrame(type, look, seed, {1397.6, 502.3}, &taught, 30);
    const auto learned = learnInImage(teach, {}, defaults, noModels(), 1, type.name, std::nullopt);
    INFO((learned.ok() ? std::string() : learned.error().message));
    REQUIRE(learned.ok());
    CHECK(learned->model.body.holes == 0);
    CHECK(std::hypot(learned->model.trained_centroid.x - taught.x,
                     learned->model.trained_centroid.y - taught.y) < 0.5);
    // Found elsewhere in the frame, turned, on the grain. LOCATE reads the
    // frame with the window the part's reach asks for, and there a darker
    // streak can join the part and run on to the frame's edge (seed 7
    // turned 170): the part is found in that region as among parts that
    // touch (RegionOptions::border_min_area; missed before).
    for (const int turn : {30, 100, 170}) {
      CAPTURE(turn);
      cv::Point2d centre;
      const cv::Mat scene =
          ps::renderSilhouetteInFrame(type, look, seed + 10, {579.3, 559.3}, &centre, turn);
      const LocateOutcome outcome =
          locateInFrame(frameFromImage(scene, "cam0", 1), defaults, listOf(learned->model), -1);
      CHECK(outcome.parts.size() == 1);
      for (const auto& p : outcome.parts) {
        CHECK(p.type == 1);
        CHECK(std::hypot(p.x - centre.x, p.y - centre.y) < 0.3);
      }
    }
  }
}

namespace {
// `image` with a tray's wall along its left edge, as dark as the part of
// `dark` (255 on the pixels darker than half-way from the part's level to
// the surface's) that holds pixel `part`, reaching `overlap_px` into the
// part's leftmost pixel: the part lies against the wall, and one region
// joins them, cut by the frame's edge. The wall's edge blurred as the
// lens blurs the part's, its levels as noisy as the camera's.
cv::Mat againstWall(const cv::Mat& image, const cv::Mat& dark, cv::Point part, int overlap_px) {
  cv::Mat labels;
  cv::connectedComponents(dark, labels, 8, CV_32S);
  const cv::Mat own = labels == labels.at<int>(part);
  const cv::Rect box = cv::boundingRect(own);
  REQUIRE(box.x > 2 * overlap_px);
  const int wall = box.x + overlap_px;
  const double level = cv::mean(image, own)[0];
  cv::Mat alpha(image.size(), CV_32F, cv::Scalar(0));
  alpha.colRange(0, wall).setTo(1);
  cv::GaussianBlur(alpha, alpha, {0, 0}, 0.7);
  // The wall's own noise, as the camera's on the part (3 grey levels).
  cv::Mat wall_levels(image.size(), CV_32F);
  cv::RNG(part.x + part.y).fill(wall_levels, cv::RNG::NORMAL, level, 3.0);
  cv::Mat out;
  image.convertTo(out, CV_32F);
  out = out.mul(1 - alpha) + alpha.mul(wall_levels);
  out.convertTo(out, CV_8U);
  return out;
}
}  // namespace

TEST_CASE("a part against a tray's wall at the frame's edge is found but not one the edge cuts",
          "[vision_app][locate][front][sweep]") {
  // A tray's wall along the left of the frame, as dark as the parts, and a
  // part lying against it: one region runs from the part off the frame.
  // LOCATE left every region the frame's edge cuts out (a part cut by it
  // cannot be located), and the part with it. Two public silhouettes
  // (Tari-1000: a hand, an umbrella) on a textured belt, taught with LEARN
  // AT, the vision app's defaults.
  const ps::SilhouetteType hand = drawing("shapes/tari1000/obj11_1.png", 220);
  const ps::SilhouetteType umbrella = drawing("shapes/tari1000/obj25_1.png", 220);
  const ps::SilhouetteSceneOptions look = lookOf("textured");
  const auto models = teachEach({hand, umbrella}, look, 300);
  const VisionOptions defaults;
  for (const int turn : {0, 75, 160, 250}) {
    for (const uint64_t seed : {3, 4}) {
      CAPTURE(turn, seed);
      const ps::SilhouetteType& type = seed == 3 ? hand : umbrella;
      cv::Point2d centre;
      const cv::Mat lone =
          ps::renderSilhouetteInFrame(type, look, seed, {260.4, 530.7}, &centre, turn);
      // The part's pixel nearest its centroid (which may lie off it).
      cv::Mat dark;
      cv::threshold(lone, dark, 0.5 * (look.part_level + look.background_level), 255,
                    cv::THRESH_BINARY_INV);
      std::vector<cv::Point> on;
      cv::findNonZero(dark(cv::Rect(100, 370, 320, 320)), on);
      REQUIRE(!on.empty());
      cv::Point nearest = on.front() + cv::Point(100, 370);
      for (const auto& p : on) {
        const cv::Point q = p + cv::Point(100, 370);
        if (std::hypot(q.x - centre.x, q.y - centre.y) <
            std::hypot(nearest.x - centre.x, nearest.y - centre.y)) {
          nearest = q;
        }
      }
      const cv::Mat scene = againstWall(lone, dark, nearest, 3);
      const LocateOutcome outcome =
          locateInFrame(frameFromImage(scene, "cam0", 1), defaults, models, -1);
      REQUIRE(outcome.parts.size() == 1);
      CHECK(outcome.parts[0].type == (seed == 3 ? 1 : 2));
      CHECK(std::hypot(outcome.parts[0].x - centre.x, outcome.parts[0].y - centre.y) < 0.5);
    }
  }
  // A part the frame's edge cuts, against nothing, by 3, 8 or 40 px: not
  // reported, whichever way it lies. (Cut by a few pixels, its region
  // passes the model's area and shape tests, and most of its outline
  // verifies: a part partly hidden, for the search of parts that touch.)
  for (const int turn : {0, 90, 180, 270}) {
    // How far the part reaches below its centroid, lying this way.
    cv::Point2d centre;
    cv::Mat whole = ps::renderSilhouetteInFrame(hand, look, 5, {960.2, 540.4}, &centre, turn);
    cv::threshold(whole, whole, 0.5 * (look.part_level + look.background_level), 255,
                  cv::THRESH_BINARY_INV);
    const cv::Rect reach = cv::boundingRect(whole(cv::Rect(800, 380, 320, 320)));
    const double below = 380 + reach.br().y - centre.y;
    for (const int cut_px : {3, 8, 40}) {
      CAPTURE(turn, cut_px);
      const cv::Mat cut = ps::renderSilhouetteInFrame(
          hand, look, 5, {960.2, 1080 - below + cut_px + 0.4}, &centre, turn);
      const LocateOutcome outcome =
          locateInFrame(frameFromImage(cut, "cam0", 1), defaults, models, -1);
      CHECK(outcome.parts.empty());
    }
  }
}

TEST_CASE("the front-light benchmark's speckled corner at 30 levels holds no part",
          "[vision_app][locate][front][sweep]") {
  // picksight-bench-front-light --conditions low-contrast --arrangements
  // touching, scene 1, as the benchmark makes it: 14 public silhouettes
  // (Tari-1000, their third drawings) taught as the benchmark teaches them
  // (LEARN on the part alone under the same light, else LEARN AT), 20
  // parts touching by pairs, distractors among them. The top right corner, dark
  // with the vignette, is a speckled region the frame's edge cuts (73116
  // px, 424 holes) whose outline steps along 23 % of its length: searched
  // for parts, it gave a part of obj6 where none lies (and cost 128 ms).
  const std::vector<std::pair<std::string, double>> specs = {
      {"obj1_3", 220},  {"obj3_3", 200},  {"obj5_3", 240},  {"obj6_3", 210},  {"obj8_3", 230},
      {"obj11_3", 200}, {"obj13_3", 220}, {"obj15_3", 250}, {"obj18_3", 190}, {"obj22_3", 230},
      {"obj25_3", 210}, {"obj27_3", 240}, {"obj35_3", 200}, {"obj45_3", 220}};
  std::vector<ps::SilhouetteType> types;
  for (const auto& [file, size] : specs) {
    types.push_back(drawing("shapes/tari1000/" + file + ".png", size));
  }
  const ps::SilhouetteSceneOptions look = lookOf("low-contrast");
  const VisionOptions defaults;
  auto models = std::make_shared<ModelList>();
  std::vector<bool> chiral;
  for (size_t i = 0; i < types.size(); ++i) {
    // The benchmark's spot for the part in its teach frame.
    std::mt19937_64 rng(0x7465616368ULL + 131 * i);
    const double margin = 0.75 * specs[i].second + 20;
    std::uniform_real_distribution<double> x(margin, look.width - 1 - margin);
    std::uniform_real_distribution<double> y(margin, look.height - 1 - margin);
    const double at_x = x(rng);
    const cv::Point2d spot(at_x, y(rng));
    cv::Point2d drawn;
    const cv::Mat teach = ps::renderSilhouetteInFrame(types[i], look, 7 + i, spot, &drawn, 30);
    const int type = static_cast<int>(i) + 1;
    auto learned = learnInImage(teach, {}, defaults, models, type, specs[i].first, std::nullopt);
    if (!learned.ok()) {
      learned = learnInImage(teach, {}, defaults, models, type, specs[i].first,
                             boxAround(drawn, specs[i].second));
    }
    INFO(specs[i].first << ": " << (learned.ok() ? std::string() : learned.error().message));
    REQUIRE(learned.ok());
    chiral.push_back(!learned->model.body.mirror_symmetric);
    models->push_back(learned->model);
  }
  ps::SilhouetteSceneOptions o = look;
  o.arrangement = ps::Arrangement::kTouching;
  o.seed = 5000 * (static_cast<uint64_t>(ps::Arrangement::kTouching) + 1) + 1;
  const ps::SilhouetteScene scene(types, chiral, o);
  const LocateOutcome outcome =
      locateInFrame(frameFromImage(scene.render(0), "cam0", 1), defaults, models, -1);
  // The corner is there, and searched for nothing.
  const auto corner = std::find_if(
      outcome.scene.regions.begin(), outcome.scene.regions.end(), [](const pv::Region& r) {
        return r.touches_border && r.holes > 100 && r.bbox.x > 1000 && r.bbox.y == 0;
      });
  CHECK(corner != outcome.scene.regions.end());
  int found = 0;
  for (const auto& p : outcome.parts) {
    CAPTURE(p.type, p.x, p.y);
    const bool drawn = std::any_of(scene.truth().begin(), scene.truth().end(), [&](const auto& t) {
      return t.kind == ps::PartKind::kTrue && static_cast<int>(t.type) + 1 == p.type &&
             std::hypot(t.centre.x - p.x, t.centre.y - p.y) < 2;
    });
    CHECK(drawn);
    found += drawn ? 1 : 0;
  }
  // And every part drawn whole of a taught type (the others are
  // distractors: mirror images, other sizes).
  const auto drawn_true =
      std::count_if(scene.truth().begin(), scene.truth().end(),
                    [](const auto& t) { return t.kind == ps::PartKind::kTrue; });
  CHECK(found == drawn_true);
}

TEST_CASE("LEARN names a shadow only where one lies beside the part, an uneven surface otherwise",
          "[vision_app][learn][front][sweep]") {
  // At 30 grey levels of contrast a blotched belt, paving bricks and gravel
  // lie a quarter of the contrast off the surface's level along a tenth or
  // a fifth of a part's outline, as a cast shadow does: LEARN called each of
  // them "a shadow or uneven light" and told the user to light the cell
  // along the camera's axis, which changes nothing there. A shadow is named
  // only where the region pass cut one off the part, from whichever side
  // the lamp casts it.
  const std::vector<std::pair<std::string, double>> files = {
      {"shapes/tari1000/obj3_11.png", 220},
      {"shapes/tari1000/obj16_11.png", 230},
      {"shapes/tari1000/obj27_11.png", 210},
      {"shapes/kimia99/trainimage6_11.png", 230}};
  const auto warningsOf = [&](const ps::SilhouetteSceneOptions& look, size_t i) {
    const ps::SilhouetteType type = drawing(files[i].first, files[i].second);
    cv::Point2d drawn;
    const cv::Mat teach =
        ps::renderSilhouetteInFrame(type, look, 20 + i, {300.0 + 330 * i, 540.5}, &drawn, 30);
    const auto learned = learnInImage(teach, {}, VisionOptions{}, noModels(), 1, "part",
                                      boxAround(drawn, files[i].second));
    REQUIRE(learned.ok());
    for (const auto& w : learned->warnings) UNSCOPED_INFO(files[i].first << ": " << w);
    return learned->warnings;
  };
  int uneven = 0;
  for (const std::string condition : {"low-contrast", "brick", "gravel"}) {
    const ps::SilhouetteSceneOptions look =
        condition == "low-contrast" ? lookOf(condition) : photographedLook(condition);
    for (size_t i = 0; i < files.size(); ++i) {
      CAPTURE(condition, files[i].first);
      const auto warnings = warningsOf(look, i);
      CHECK_FALSE(mentions(warnings, "shadow beside"));
      uneven += mentions(warnings, "an uneven surface") ? 1 : 0;
    }
  }
  // Most of them see the surface's unevenness, and say so.
  CHECK(uneven >= 6);
  for (const double lamp : {45.0, 220.0}) {
    ps::SilhouetteSceneOptions look = lookOf("shadow");
    look.front.shadow_angle_deg = lamp;
    for (size_t i = 0; i < files.size(); ++i) {
      CAPTURE(lamp, files[i].first);
      CHECK(mentions(warningsOf(look, i), "a shadow beside the part"));
    }
  }
}
