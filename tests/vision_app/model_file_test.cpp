// Model files and the model library: round trip, atomic replacement, bad
// files rejected with a message naming the file and the problem.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "picksight/app/vision_cell.hpp"
#include "picksight/common/atomic_file.hpp"
#include "picksight/protocol/model_commands.hpp"
#include "picksight/store/model_file.hpp"
#include "picksight/store/model_library.hpp"
#include "picksight/synthetic/scene.hpp"

using namespace picksight;
using namespace picksight::app;
using namespace picksight::cell;
using namespace picksight::store;
namespace fs = std::filesystem;

namespace {
vision::PartModel trainedModel(const std::string& type, int id) {
  synthetic::SceneOptions o;
  o.width = 400;
  o.height = 400;
  o.parts = 1;
  o.types = {type};
  const synthetic::SceneRenderer scene(o);
  auto outcome = vision::trainModel(scene.render(0), id, type);
  REQUIRE(outcome.ok());
  return outcome.value();
}

struct TempDir {
  TempDir() {
    char pattern[] = "/tmp/picksight-models-XXXXXX";
    path = ::mkdtemp(pattern);
  }
  ~TempDir() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
  std::string path;
};

void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }
}  // namespace

TEST_CASE("a model survives its file unchanged", "[vision_app][models]") {
  const auto model = trainedModel("slot", 7);
  const std::string text = modelToYaml(model);
  CHECK(text.find("version: 2") != std::string::npos);
  auto back = modelFromYaml(text);
  REQUIRE(back);
  CHECK(back->type == 7);
  CHECK(back->name == "slot");
  CHECK(back->body.area == Approx(model.body.area));
  CHECK(back->body.log_hu == model.body.log_hu);
  CHECK(back->body.hu_used == model.body.hu_used);
  CHECK(back->body.mirror_symmetric == model.body.mirror_symmetric);
  CHECK(back->orientation_order == model.orientation_order);
  CHECK(back->symmetry_order == model.symmetry_order);
  REQUIRE(back->loops.size() == model.loops.size());
  for (size_t i = 0; i < model.loops.size(); ++i) {
    REQUIRE(back->loops[i].primitives.size() == model.loops[i].primitives.size());
    for (size_t j = 0; j < model.loops[i].primitives.size(); ++j) {
      CHECK(back->loops[i].primitives[j].kind == model.loops[i].primitives[j].kind);
      CHECK(back->loops[i].primitives[j].length() == Approx(model.loops[i].primitives[j].length()));
    }
  }
  CHECK(back->corners.size() == model.corners.size());
  CHECK(back->samples.size() == model.samples.size());  // prepared on load
  CHECK(modelToYaml(*back) == text);
}

TEST_CASE("grasps travel with the model and version 1 files still load", "[vision_app][models]") {
  const auto model = trainedModel("rectangle", 4);
  const GraspSetup grasp{{{1.5, -2, 90}, {0, 3, 180}}, {{{-10, 0, 4, 8}, {10, 0, 4, 8}}}};
  auto back = modelRecordFromYaml(modelToYaml(model, grasp));
  REQUIRE(back);
  REQUIRE(back->grasp.styles.size() == 2);
  CHECK(back->grasp.styles[0].x_mm == 1.5);
  CHECK(back->grasp.styles[1].rz_deg == 180);
  REQUIRE(back->grasp.gripper.fingers.size() == 2);
  CHECK(back->grasp.gripper.fingers[1].height_mm == 8);
  // A version 1 file: the same model without the grasp section.
  std::string v1 = modelToYaml(model);
  v1.replace(v1.find("version: 2"), 10, "version: 1");
  v1.erase(v1.find("grasp:"));
  auto old = modelRecordFromYaml(v1);
  REQUIRE(old);
  CHECK(old->model.type == 4);
  CHECK(old->grasp.styles.empty());
  CHECK(old->grasp.gripper.fingers.empty());
  // The grasp section is required from version 2 on.
  std::string v2_without = v1;
  v2_without.replace(v2_without.find("version: 1"), 10, "version: 2");
  CHECK_FALSE(modelRecordFromYaml(v2_without));

  TempDir dir;
  {
    ModelLibrary library(dir.path + "/models");
    REQUIRE(library.store(model));
    CHECK_FALSE(library.setGrasp(5, grasp));  // no model of type 5
    REQUIRE(library.setGrasp(4, grasp));
    REQUIRE(library.store(model));  // re-trained: keeps its grasps
    CHECK(library.graspOf(4).styles.size() == 2);
  }
  ModelLibrary reloaded(dir.path + "/models");
  CHECK(reloaded.load().empty());
  CHECK(reloaded.graspOf(4).gripper.fingers.size() == 2);
  REQUIRE(reloaded.remove(4));
  CHECK(reloaded.graspOf(4).styles.empty());
}

TEST_CASE("bad model files are rejected with the problem", "[vision_app][models]") {
  const std::string good = modelToYaml(trainedModel("rectangle", 1));
  CHECK_FALSE(modelFromYaml("{{{ not yaml"));
  CHECK_FALSE(modelFromYaml("just a string"));
  CHECK_FALSE(modelFromYaml(""));
  std::string v3 = good;
  v3.replace(v3.find("version: 2"), 10, "version: 3");
  auto r = modelFromYaml(v3);
  REQUIRE_FALSE(r);
  CHECK(r.error().message.find("version 3") != std::string::npos);
  std::string bad_finger =
      modelToYaml(trainedModel("rectangle", 1), GraspSetup{{}, {{{0, 0, -1, 2}}}});
  r = modelFromYaml(bad_finger);
  REQUIRE_FALSE(r);
  CHECK(r.error().message.find("finger") != std::string::npos);
  std::string no_area = good;
  no_area.replace(no_area.find("  area:"), 7, "  aera:");
  r = modelFromYaml(no_area);
  REQUIRE_FALSE(r);
  CHECK(r.error().message.find("'area'") != std::string::npos);
  std::string bad_verify = good;
  const size_t at = bad_verify.find("verify_percent: ");
  bad_verify.replace(at, bad_verify.find('\n', at) - at, "verify_percent: 250");
  r = modelFromYaml(bad_verify);
  REQUIRE_FALSE(r);
  CHECK(r.error().message.find("verify percent") != std::string::npos);
  std::string nan_area = good;
  const size_t a = nan_area.find("  area: ");
  nan_area.replace(a, nan_area.find('\n', a) - a, "  area: .nan");
  CHECK_FALSE(modelFromYaml(nan_area));
}

TEST_CASE("a model file whose symmetry order its boundary does not have is rejected",
          "[vision_app][models]") {
  // The order sets the range the part's angles are reported in: an L
  // taken for half-turn symmetric would be gripped a half turn wrong one
  // time in two. Its file is refused naming the order, as any bad value.
  const std::string ell = modelToYaml(trainedModel("l_shape", 3));
  const std::string order = "symmetry_order: 1";
  REQUIRE(ell.find(order) != std::string::npos);
  REQUIRE(modelFromYaml(ell));
  std::string tampered = ell;
  tampered.replace(tampered.find(order), order.size(), "symmetry_order: 2");
  const auto r = modelFromYaml(tampered);
  REQUIRE_FALSE(r);
  CHECK(r.error().code == ModelErrc::kBadFile);
  CHECK(r.error().message.find("symmetry order 2 does not fit the boundary") != std::string::npos);
  // A bar's half-turn symmetry is its own.
  const std::string bar = modelToYaml(trainedModel("rectangle", 4));
  REQUIRE(bar.find("symmetry_order: 2") != std::string::npos);
  CHECK(modelFromYaml(bar));
}

TEST_CASE("the library stores, reloads, forgets, and skips bad files by name",
          "[vision_app][models]") {
  TempDir dir;
  const std::string models_dir = dir.path + "/models";
  {
    ModelLibrary library(models_dir);
    CHECK(library.load().empty());
    REQUIRE(library.store(trainedModel("rectangle", 1)));
    REQUIRE(library.store(trainedModel("l_shape", 2)));
    CHECK(library.snapshot()->size() == 2);
    CHECK(fs::exists(library.pathOf(1)));
    // Replacing a type keeps one model of it.
    REQUIRE(library.store(trainedModel("l_shape", 1)));
    CHECK(library.snapshot()->size() == 2);
  }
  writeText(models_dir + "/broken.yaml", "format: picksight-part-model\nversion: 1\ntype: [\n");
  writeText(models_dir + "/other.yaml", "format: something-else\n");
  writeText(models_dir + "/notes.txt", "not a model, not even looked at\n");
  ModelLibrary library(models_dir);
  const auto problems = library.load();
  REQUIRE(problems.size() == 2);
  CHECK(problems[0].find("broken.yaml") != std::string::npos);
  CHECK(problems[1].find("other.yaml") != std::string::npos);
  REQUIRE(library.snapshot()->size() == 2);
  CHECK(library.snapshot()->at(0).name == "l_shape");
  REQUIRE(library.remove(2));
  CHECK_FALSE(fs::exists(library.pathOf(2)));
  CHECK_FALSE(library.remove(2));
  CHECK(library.snapshot()->size() == 1);
}

TEST_CASE("model commands check their arguments before touching the camera",
          "[vision_app][protocol]") {
  TempDir dir;
  VisionCell protocol{dir.path, std::make_unique<picksight::link::NoCamera>(), VisionOptions{}};
  ModelLibrary& library = protocol.models();
  CHECK(protocol.handle("MODELS") == "OK 0");
  CHECK(protocol.handle("MODELS 1").rfind("ERROR 11 ", 0) == 0);
  CHECK(protocol.handle("LEARN").rfind("ERROR 11 ", 0) == 0);
  CHECK(protocol.handle("LEARN x").rfind("ERROR 11 ", 0) == 0);
  CHECK(protocol.handle("LEARN 1 bad/name").rfind("ERROR 11 ", 0) == 0);
  CHECK(protocol.handle("LEARN 1 a b").rfind("ERROR 11 ", 0) == 0);
  CHECK(protocol.handle("FORGET").rfind("ERROR 11 ", 0) == 0);
  CHECK(protocol.handle("FORGET 3").rfind("ERROR 32 ", 0) == 0);
  CHECK(protocol.handle("BLOBS 1").rfind("ERROR 11 ", 0) == 0);
  CHECK(protocol.handle("HELP").find("LEARN <type> [name]") != std::string::npos);
  REQUIRE(library.store(trainedModel("rectangle", 1)));
  const std::string models = protocol.handle("models");
  CHECK(models.rfind("OK 1 1 rectangle ", 0) == 0);
  CHECK(models.find(" 180.000") != std::string::npos);
  // A type without a model is refused at once, without a frame.
  CHECK(protocol.handle("LOCATE 2").rfind("ERROR 32 ", 0) == 0);
  CHECK(protocol.handle("FORGET 1") == "OK");
  CHECK(protocol.handle("MODELS") == "OK 0");
}

TEST_CASE("the library loads models in type order, not file-name order", "[vision_app][models]") {
  TempDir dir;
  const std::string models_dir = dir.path + "/models";
  {
    ModelLibrary library(models_dir);
    for (int type : {100, 2, 10, 1}) REQUIRE(library.store(trainedModel("rectangle", type)));
  }
  // A second file for type 2 under another name: type_2.yaml, where LEARN
  // writes, wins whatever the names' order.
  auto other = trainedModel("l_shape", 2);
  writeText(models_dir + "/a_copy.yaml", modelToYaml(other));
  ModelLibrary library(models_dir);
  const auto problems = library.load();
  REQUIRE(problems.size() == 1);
  CHECK_THAT(problems[0], Catch::Contains("a_copy.yaml") && Catch::Contains("type 2"));
  std::vector<int> types;
  for (const auto& m : *library.snapshot()) types.push_back(m.type);
  CHECK(types == std::vector<int>{1, 2, 10, 100});
  CHECK(library.snapshot()->at(1).name == "rectangle");
}

TEST_CASE("the library removes temporary files of interrupted writes at load",
          "[vision_app][models]") {
  TempDir dir;
  const std::string models_dir = dir.path + "/models";
  {
    ModelLibrary library(models_dir);
    REQUIRE(library.store(trainedModel("rectangle", 1)));
  }
  // As a crash between create and rename leaves them, by this process or another.
  writeText(models_dir + "/type_1.yaml.tmp.999999", "format: picksight-part-model\nvers");
  writeText(models_dir + "/type_2.yaml.tmp.12", "");
  writeText(models_dir + "/notes.tmp.txt", "not ours: kept");
  ModelLibrary library(models_dir);
  CHECK(library.load().empty());
  CHECK_FALSE(fs::exists(models_dir + "/type_1.yaml.tmp.999999"));
  CHECK_FALSE(fs::exists(models_dir + "/type_2.yaml.tmp.12"));
  CHECK(fs::exists(models_dir + "/notes.tmp.txt"));
  CHECK(library.snapshot()->size() == 1);
}

TEST_CASE("a models path that is a file is a problem of the load, naming it",
          "[vision_app][models]") {
  TempDir dir;
  const std::string models_dir = dir.path + "/models";
  writeText(models_dir, "a file where the models directory should be\n");
  ModelLibrary library(models_dir);
  const auto problems = library.load();
  REQUIRE(problems.size() == 1);
  CHECK_THAT(problems[0], Catch::Contains(models_dir) && Catch::Contains("not a directory"));
  CHECK(library.snapshot()->empty());
}
