// Model files and the model library: round trip, atomic replacement, bad
// files rejected with a message naming the file and the problem.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

#include "picksight/common/atomic_file.hpp"
#include "picksight/synthetic/scene.hpp"
#include "picksight/vision_app/model_commands.hpp"
#include "picksight/vision_app/model_file.hpp"
#include "picksight/vision_app/model_library.hpp"
#include "picksight/vision_app/robot_protocol.hpp"

using namespace picksight;
using namespace picksight::app;
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
  REQUIRE(outcome.ok);
  return outcome.model;
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
  CHECK(text.find("version: 1") != std::string::npos);
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

TEST_CASE("bad model files are rejected with the problem", "[vision_app][models]") {
  const std::string good = modelToYaml(trainedModel("rectangle", 1));
  CHECK_FALSE(modelFromYaml("{{{ not yaml"));
  CHECK_FALSE(modelFromYaml("just a string"));
  CHECK_FALSE(modelFromYaml(""));
  std::string v2 = good;
  v2.replace(v2.find("version: 1"), 10, "version: 2");
  auto r = modelFromYaml(v2);
  REQUIRE_FALSE(r);
  CHECK(r.error().message.find("version 2") != std::string::npos);
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
  ModelLibrary library(dir.path + "/models");
  zmq::context_t context;
  VisionService vision{context, "tcp://127.0.0.1:1", "tcp://127.0.0.1:1",
                       "cam0",  VisionOptions{},     &library};
  RobotProtocol protocol{vision};
  addModelCommands(protocol.table(), vision);
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
