// UNDO against a real video server and vision app over TCP: each change to
// models (LEARN over an existing type, a new type, FORGET, TOLERANCE, GRASP)
// taken back with the model file byte for byte as it was, the model in use
// with it; the history across a restart, bounded, refused on a read-only
// port; a damaged entry or a file edited since reported and never applied.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include "picksight/codecs/codecs.hpp"

#include "../vision/drawn_parts.hpp"
#include "cell_fixture.hpp"
#include "file_text.hpp"
#include "scene_file.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::tool_support;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {
using test::kBar;
using test::kPlate;

size_t entries(const std::string& dir, const std::string& suffix) {
  size_t n = 0;
  if (!fs::is_directory(dir)) return 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    n += name.size() > suffix.size() &&
         name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
  }
  return n;
}

// A file camera in trigger mode showing a plate, a vision app whose data
// directory outlives it, the plate learned as type 1.
struct UndoCell {
  SceneFile scene{test::aloneInFrame(kPlate)};
  std::string data_dir = scene.dir + "/data";
  VideoServerProcess server{{"--source", "cam0=file:" + scene.path, "--mode", "trigger"}};
  std::unique_ptr<VisionProcess> vision;
  std::unique_ptr<LineClient> robot;

  explicit UndoCell(std::vector<std::string> args = {}) {
    fs::create_directories(data_dir);
    restart(args);
    REQUIRE(ask("LEARN 1 plate").rfind("OK 1 plate ", 0) == 0);
  }
  void restart(const std::vector<std::string>& args = {}) {
    robot.reset();
    vision.reset();
    vision = std::make_unique<VisionProcess>(server, "cam0", data_dir, args);
    robot = std::make_unique<LineClient>(vision->connect());
  }
  std::string ask(const std::string& request) {
    auto reply = robot->request(request, 20s);
    REQUIRE(reply);
    return *reply;
  }
  std::string model(int type = 1) const {
    return test::readFileText(data_dir + "/models/type_" + std::to_string(type) + ".yaml");
  }
  std::string undoDir() const { return data_dir + "/models/undo"; }
  // The newest entry of the history.
  std::string newestEntry() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(undoDir())) {
      if (e.path().extension() == ".undo") names.push_back(e.path().string());
    }
    REQUIRE_FALSE(names.empty());
    std::sort(names.begin(), names.end());
    return names.back();
  }
};
}  // namespace

TEST_CASE("UNDO takes back a LEARN over an existing type byte for byte with its tolerances",
          "[vision_app][undo][e2e]") {
  UndoCell cell;
  REQUIRE(cell.ask("TOLERANCE 1 area_tolerance 0.2 hu_tolerance 2").rfind("OK 1 plate", 0) == 0);
  const std::string tuned = cell.model();
  const std::string tuned_tolerances = cell.ask("TOLERANCE 1");
  CHECK_THAT(tuned_tolerances, Catch::Contains("area_tolerance=0.200000"));

  // Taught again over type 1, from another part: the tuned model is replaced.
  cell.scene.show(test::aloneInFrame(kBar));
  REQUIRE(cell.ask("LEARN 1 bar").rfind("OK 1 bar ", 0) == 0);
  REQUIRE(cell.model() != tuned);
  CHECK_THAT(cell.ask("TOLERANCE 1"), Catch::Contains("area_tolerance=0.100000"));

  const std::string undone = cell.ask("UNDO");
  CHECK_THAT(undone,
             Catch::StartsWith("OK 1 restored 2 ; undid: LEARN 1 bar ; type 1 is 1 plate "));
  CHECK(cell.model() == tuned);
  // The model in use is the file's: the tuned tolerances, the plate found.
  CHECK(cell.ask("TOLERANCE 1") == tuned_tolerances);
  cell.scene.show(test::aloneInFrame(kPlate));
  CHECK(parseLocateReply(cell.ask("LOCATE 1")).size() == 1);
  cell.scene.show(test::aloneInFrame(kBar));
  CHECK(parseLocateReply(cell.ask("LOCATE 1")).empty());

  // Back past the tolerance change, then past the first LEARN: no model.
  CHECK_THAT(cell.ask("UNDO"),
             Catch::StartsWith("OK 1 restored 1 ; undid: TOLERANCE 1 area_tolerance 0.2"));
  CHECK_THAT(cell.ask("TOLERANCE 1"), Catch::Contains("area_tolerance=0.100000"));
  CHECK(cell.ask("UNDO") == "OK 1 removed 0 ; undid: LEARN 1 plate ; type 1 has no model again");
  CHECK_FALSE(fs::exists(cell.data_dir + "/models/type_1.yaml"));
  CHECK(cell.ask("MODELS") == "OK 0");
  const std::string nothing = cell.ask("UNDO");
  CHECK_THAT(nothing, Catch::StartsWith("ERROR 37 nothing to undo (the last 32 changes"));
  CHECK(cell.ask("MODELS") == "OK 0");
}

TEST_CASE("UNDO restores a forgotten model with its grasps and takes back TOLERANCE and GRASP",
          "[vision_app][undo][e2e]") {
  UndoCell cell;
  REQUIRE(cell.ask("GRASP 1 ADD 1 2 30") == "OK 1");
  const std::string with_grasp = cell.model();
  REQUIRE(cell.ask("FORGET 1") == "OK");
  REQUIRE_FALSE(fs::exists(cell.data_dir + "/models/type_1.yaml"));
  CHECK_THAT(cell.ask("UNDO"), Catch::StartsWith("OK 1 restored 2 ; undid: FORGET 1 ; type 1 is"));
  CHECK(cell.model() == with_grasp);
  CHECK(cell.ask("GRASP 1 LIST") == "OK 1 1.000 2.000 30.000");

  REQUIRE(cell.ask("TOLERANCE 1 verify_percent 55").rfind("OK", 0) == 0);
  REQUIRE(cell.model() != with_grasp);
  CHECK_THAT(cell.ask("UNDO"),
             Catch::StartsWith("OK 1 restored 2 ; undid: TOLERANCE 1 verify_percent 55"));
  CHECK(cell.model() == with_grasp);
  CHECK_THAT(cell.ask("TOLERANCE 1"), Catch::Contains("verify_percent=80.000"));

  REQUIRE(cell.ask("GRIPPER 1 FINGER 0 12 6 4") == "OK 1");
  CHECK_THAT(cell.ask("UNDO"), Catch::StartsWith("OK 1 restored 2 ; undid: GRIPPER 1 FINGER"));
  CHECK(cell.model() == with_grasp);
  CHECK(cell.ask("GRIPPER 1 LIST") == "OK 0");
  CHECK_THAT(cell.ask("UNDO"), Catch::StartsWith("OK 1 restored 1 ; undid: GRASP 1 ADD 1 2 30"));
  CHECK(cell.ask("GRASP 1 LIST") == "OK 0");
}

// The teach image beside a model: what the camera showed when it was taught.
cv::Mat teachImage(const UndoCell& cell, int type = 1) {
  return picksight::codecs::imread(cell.data_dir + "/models/type_" + std::to_string(type) + ".png",
                                   cv::IMREAD_UNCHANGED);
}

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

TEST_CASE("LEARN stores its teach image beside the model and FORGET and UNDO follow it",
          "[vision_app][undo][e2e]") {
  UndoCell cell;  // the plate learned as type 1
  const std::string png = cell.data_dir + "/models/type_1.png";
  const cv::Mat plate = test::aloneInFrame(kPlate);
  REQUIRE(fs::exists(png));
  CHECK(same(teachImage(cell), plate));
  const std::string plate_png = test::readFileText(png);

  // Taught again from the bar: its image replaces the plate's.
  cell.scene.show(test::aloneInFrame(kBar));
  REQUIRE(cell.ask("LEARN 1 bar").rfind("OK 1 bar ", 0) == 0);
  CHECK(same(teachImage(cell), test::aloneInFrame(kBar)));
  // A change that is not a teach leaves the image alone, and so does its UNDO.
  const std::string bar_png = test::readFileText(png);
  REQUIRE(cell.ask("TOLERANCE 1 area_tolerance 0.2").rfind("OK 1 bar", 0) == 0);
  CHECK(test::readFileText(png) == bar_png);
  REQUIRE(cell.ask("UNDO").rfind("OK 1 restored 2 ; undid: TOLERANCE", 0) == 0);
  CHECK(test::readFileText(png) == bar_png);
  // UNDO of the second LEARN: the plate's image again, byte for byte.
  REQUIRE(cell.ask("UNDO").rfind("OK 1 restored 1 ; undid: LEARN 1 bar", 0) == 0);
  CHECK(test::readFileText(png) == plate_png);

  REQUIRE(cell.ask("FORGET 1") == "OK");
  CHECK_FALSE(fs::exists(png));
  REQUIRE(cell.ask("UNDO").rfind("OK 1 restored 1 ; undid: FORGET 1", 0) == 0);
  CHECK(test::readFileText(png) == plate_png);
  // Back past the first LEARN: no model, no image.
  REQUIRE(cell.ask("UNDO").rfind("OK 1 removed 0 ; undid: LEARN 1 plate", 0) == 0);
  CHECK_FALSE(fs::exists(png));
  CHECK(entries(cell.undoDir(), ".png") == 0);
}

TEST_CASE("A teach image is bounded and its undo copies go with the history's entries",
          "[vision_app][undo][e2e]") {
  UndoCell cell;
  // A large frame is stored shrunk to 1024 pixels on its longer side.
  cell.scene.show(test::drawParts(2400, 1200, {{kPlate, 1200, 600, 0}}, 11));
  REQUIRE(cell.ask("LEARN 2 large").rfind("OK 2 large ", 0) == 0);
  const cv::Mat large = teachImage(cell, 2);
  CHECK(large.cols == 1024);
  CHECK(large.rows == 512);

  // 34 more teaches: the history keeps 32 entries, and as many images.
  for (int i = 0; i < 34; ++i) REQUIRE(cell.ask("LEARN 2 large").rfind("OK 2 large ", 0) == 0);
  CHECK(entries(cell.undoDir(), ".undo") == 32);
  CHECK(entries(cell.undoDir(), ".png") == 32);
}

TEST_CASE("UNDO's history survives a restart and is bounded to 32 changes",
          "[vision_app][undo][e2e]") {
  UndoCell cell;
  const std::string learned = cell.model();
  REQUIRE(cell.ask("TOLERANCE 1 area_tolerance 0.3").rfind("OK", 0) == 0);
  cell.restart();
  CHECK_THAT(cell.ask("UNDO"), Catch::StartsWith("OK 1 restored 1 ; undid: TOLERANCE 1"));
  CHECK(cell.model() == learned);

  // 40 changes: the history keeps the newest 32, the oldest go.
  std::vector<std::string> files{cell.model()};
  for (int i = 0; i < 40; ++i) {
    REQUIRE(cell.ask("TOLERANCE 1 verify_percent " + std::to_string(50 + i)).rfind("OK", 0) == 0);
    files.push_back(cell.model());
  }
  CHECK(entries(cell.undoDir(), ".undo") == 32);
  for (int i = 40; i > 8; --i) {
    REQUIRE(cell.ask("UNDO").rfind("OK 1 restored " + std::to_string(i - 9), 0) == 0);
    REQUIRE(cell.model() == files[static_cast<size_t>(i - 1)]);
  }
  CHECK_THAT(cell.ask("UNDO"), Catch::StartsWith("ERROR 37 "));
  CHECK(cell.model() == files[8]);
}

TEST_CASE("UNDO refuses a damaged entry or a file edited since and goes on past them",
          "[vision_app][undo][e2e]") {
  UndoCell cell;
  const std::string learned = cell.model();
  REQUIRE(cell.ask("TOLERANCE 1 area_tolerance 0.3").rfind("OK", 0) == 0);
  const std::string tuned = cell.model();

  SECTION("a byte of the newest entry's old file flipped") {
    REQUIRE(cell.ask("TOLERANCE 1 area_tolerance 0.4").rfind("OK", 0) == 0);
    const std::string tuned_again = cell.model();
    // Type 2 (the same part: LEARN warns it looks like type 1) is taught over.
    REQUIRE(cell.ask("LEARN 2 first").rfind("OK 2 first", 0) == 0);
    REQUIRE(cell.ask("LEARN 2 second").rfind("OK 2 second", 0) == 0);
    const std::string second = cell.model(2);
    const std::string entry = cell.newestEntry();
    std::string bytes = test::readFileText(entry);
    bytes[bytes.size() - 10] ^= 0x01;
    std::ofstream(entry, std::ios::binary | std::ios::trunc) << bytes;
    cell.restart();  // the start's log names it (not checked here)
    const std::string refused = cell.ask("UNDO");
    CHECK_THAT(refused, Catch::StartsWith("ERROR 38 undo history entry " +
                                          fs::path(entry).filename().string() + " is damaged"));
    CHECK_THAT(refused, Catch::Contains("not applied, nothing changed; set aside as"));
    CHECK(cell.model(2) == second);
    CHECK(fs::exists(entry + ".damaged"));
    // The change before it was type 2's first LEARN: its file is not what
    // that LEARN left, so it is refused too, never applied over the second.
    CHECK_THAT(cell.ask("UNDO"), Catch::StartsWith("ERROR 38 type 2's model file is not what "
                                                   "'LEARN 2 first' left"));
    CHECK(cell.model(2) == second);
    // Type 1's changes before them still apply.
    CHECK_THAT(cell.ask("UNDO"), Catch::StartsWith("OK 1 restored 2 ; undid: TOLERANCE 1 "
                                                   "area_tolerance 0.4"));
    CHECK(cell.model() == tuned);
    CHECK_THAT(cell.ask("UNDO"), Catch::StartsWith("OK 1 restored 1 ; undid: TOLERANCE 1 "
                                                   "area_tolerance 0.3"));
    CHECK(cell.model() == learned);
    (void)tuned_again;
  }
  SECTION("the model file edited by hand since the change") {
    const std::string path = cell.data_dir + "/models/type_1.yaml";
    std::ofstream(path, std::ios::binary | std::ios::app) << "# tuned by hand\n";
    const std::string edited = cell.model();
    const std::string refused = cell.ask("UNDO");
    CHECK_THAT(refused, Catch::StartsWith("ERROR 38 type 1's model file is not what 'TOLERANCE 1 "
                                          "area_tolerance 0.3' left"));
    CHECK(cell.model() == edited);
    CHECK(entries(cell.undoDir(), ".damaged") == 1);
    CHECK_THAT(cell.ask("UNDO"), Catch::StartsWith("ERROR 38 "));
    CHECK(cell.model() == edited);
    CHECK_THAT(cell.ask("UNDO"), Catch::StartsWith("ERROR 37 "));
  }
}

TEST_CASE("UNDO is refused on a read-only port", "[vision_app][undo][e2e]") {
  UndoCell cell;
  REQUIRE(cell.ask("TOLERANCE 1 area_tolerance 0.3").rfind("OK", 0) == 0);
  const std::string tuned = cell.model();
  cell.restart({"--robot-read-only"});
  CHECK_THAT(cell.ask("UNDO"), Catch::StartsWith("ERROR 17 UNDO changes the cell"));
  CHECK(cell.model() == tuned);
}
