// The filmstrip against a real video server and vision app over TCP: each
// LOCATE and WHY kept with its frame; REPLAY of a stored frame answers as
// the LOCATE did while the models are the same, and as the models in use
// answer after a re-teach; bad ids and a damaged sidecar get an ERROR and
// the app goes on; the export served by a dir: camera; test-run's table and
// exit status over the exported frames.
#include <catch2/catch.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "../vision/drawn_parts.hpp"
#include "cell_fixture.hpp"
#include "picksight/common/text.hpp"
#include "scene_file.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::tool_support;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {
using test::kBar;
using test::kPlate;

// A file camera in trigger mode, a vision app with its filmstrip, the plate
// learned as type 1.
struct FilmCell {
  SceneFile scene{test::aloneInFrame(kPlate)};
  VideoServerProcess server{{"--source", "cam0=file:" + scene.path, "--mode", "trigger"}};
  // Every success recorded (by default, one a second at most).
  VisionProcess vision{server, "cam0", "", {"--filmstrip-success-ms", "0"}};
  LineClient robot = vision.connect();

  FilmCell() { REQUIRE(ask("LEARN 1 plate").rfind("OK 1 plate ", 0) == 0); }
  std::string ask(const std::string& request) {
    auto reply = robot.request(request, 20s);
    REQUIRE(reply);
    return *reply;
  }
  // Waits for the writer thread to have written `n` entries in all.
  void written(size_t n) {
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    for (;;) {
      const std::string status = ask("FILMSTRIP STATUS");
      if (status.find(" recorded=" + std::to_string(n) + " ") != std::string::npos) return;
      REQUIRE(std::chrono::steady_clock::now() < deadline);
      std::this_thread::sleep_for(20ms);
    }
  }
  std::string strip() const { return vision.data_dir + "/filmstrip"; }
};
}  // namespace

TEST_CASE("REPLAY answers as the LOCATE did with the same models, and as today's after a re-teach",
          "[vision_app][filmstrip][e2e]") {
  FilmCell cell;
  const std::string found = cell.ask("LOCATE 1");
  REQUIRE(parseLocateReply(found).size() == 1);
  cell.scene.show(test::aloneInFrame(kBar));
  const std::string missed = cell.ask("LOCATE 1");
  REQUIRE(missed == "OK 0");
  const std::string why = cell.ask("WHY");
  // The bar, far from the plate taught in area and holes, unlike any part:
  // the one region, said whole.
  REQUIRE_THAT(why, Catch::StartsWith("OK 1 region 0 "));
  cell.written(3);
  // Newest first; the miss and the WHY kept as failures.
  CHECK(cell.ask("FILMSTRIP") == "OK 3 3 WHY fail 2 LOCATE fail 1 LOCATE ok");
  CHECK(cell.ask("FILMSTRIP 1 FAILURES") == "OK 1 3 WHY fail");
  const std::string shown = cell.ask("FILMSTRIP SHOW 2");
  CHECK_THAT(shown, Catch::Contains("\"reply\":\"OK 0\""));
  CHECK_THAT(shown, Catch::Contains("\"request_line\":\"LOCATE 1\""));
  // The failed LOCATE's entry explains itself as WHY did.
  CHECK_THAT(shown, Catch::Contains("\"why\":\"" + why + "\""));
  CHECK_THAT(cell.ask("FILMSTRIP SHOW 3"), Catch::Contains("\"explains\":2"));

  // The same models: the same answers, and the camera is not asked.
  CHECK(cell.ask("REPLAY 1") == found);
  CHECK(cell.ask("REPLAY 2") == missed);
  CHECK(cell.ask("REPLAY 3") == missed);  // a WHY replays its LOCATE
  const std::string all = cell.ask("REPLAY 1 ALL");
  CHECK_THAT(all, Catch::StartsWith("OK 1 1 "));
  CHECK(cell.ask("FILMSTRIP STATUS").find(" recorded=3 ") != std::string::npos);

  // Taught again on the bar: the frame that failed is a success now, the
  // frame that succeeded fails.
  REQUIRE(cell.ask("LEARN 1 bar").rfind("OK 1 bar ", 0) == 0);
  CHECK(parseLocateReply(cell.ask("REPLAY 2")).size() == 1);
  CHECK(cell.ask("REPLAY 1") == "OK 0");
  CHECK(cell.ask("REPLAY 1 2") == "ERROR 32 no model for type 2 (see MODELS)");
}

TEST_CASE("FILMSTRIP and REPLAY refuse bad ids and report a damaged sidecar, and the app goes on",
          "[vision_app][filmstrip][e2e]") {
  FilmCell cell;
  REQUIRE(parseLocateReply(cell.ask("LOCATE 1")).size() == 1);
  cell.written(1);
  for (const std::string bad :
       {"REPLAY", "REPLAY 0", "REPLAY -1", "REPLAY 12345678901", "REPLAY x", "REPLAY 1 ALL 2",
        "REPLAY 1 10000", "FILMSTRIP 0", "FILMSTRIP 101", "FILMSTRIP SHOW", "FILMSTRIP SHOW 1x",
        "FILMSTRIP IMAGE 1 15", "FILMSTRIP EXPORT .hidden", "FILMSTRIP EXPORT a/b",
        "FILMSTRIP STATUS 1"}) {
    INFO(bad);
    CHECK_THAT(cell.ask(bad), Catch::StartsWith("ERROR 11 "));
  }
  CHECK(cell.ask("REPLAY 7") == "ERROR 55 no filmstrip entry 7 (see FILMSTRIP)");
  CHECK_THAT(cell.ask("FILMSTRIP SHOW 7"), Catch::StartsWith("ERROR 55 "));
  const std::string image = cell.ask("FILMSTRIP IMAGE 1 64");
  CHECK_THAT(image, Catch::StartsWith("OK 64 48 iVBORw0KGgo"));  // a PNG, 640x480 shrunk

  std::ofstream(cell.strip() + "/0000000001.json") << "{\"id\": 1, \"reply\": [";
  const std::string damaged = cell.ask("REPLAY 1");
  CHECK_THAT(damaged, Catch::StartsWith("ERROR 56 "));
  CHECK_THAT(damaged, Catch::Contains("0000000001.json"));
  CHECK_THAT(cell.ask("FILMSTRIP SHOW 1"), Catch::StartsWith("ERROR 56 "));
  // The app goes on recording and answering.
  REQUIRE(parseLocateReply(cell.ask("LOCATE 1")).size() == 1);
  cell.written(2);
  CHECK_THAT(cell.ask("REPLAY 2"), Catch::StartsWith("OK 1 "));
}

TEST_CASE("a filmstrip export is served by a dir: camera and checked by test-run",
          "[vision_app][filmstrip][e2e]") {
  FilmCell cell;
  REQUIRE(parseLocateReply(cell.ask("LOCATE 1")).size() == 1);
  cell.scene.show(test::aloneInFrame(kBar));
  REQUIRE(cell.ask("LOCATE 1") == "OK 0");
  REQUIRE_THAT(cell.ask("WHY"), Catch::StartsWith("OK 1 "));
  cell.written(3);
  const std::string exported = cell.ask("FILMSTRIP EXPORT run1");
  const std::string path = cell.strip() + "/exports/run1";
  // The two LOCATEs' frames; the WHY shares the second's.
  CHECK(exported == "OK 2 " + path);
  CHECK_THAT(cell.ask("FILMSTRIP EXPORT run1"), Catch::StartsWith("ERROR 58 "));

  // A test run of the plate model over them: one image passes, one fails.
  auto run = e2e::run({binPath("picksight-vision"), "test-run", "--models", cell.vision.data_dir,
                       "--images", path, "--expect", "1", "--type", "1"});
  INFO(run.out);
  CHECK(run.exit_code == 1);
  const auto lines = splitFields(run.out, "\n");
  REQUIRE(lines.size() == 4);
  CHECK(lines[0] == "image       found  expected  result");
  CHECK(lines[1] == "000001.png      1         1  pass");
  CHECK(lines[2] == "000002.png      0         1  FAIL");
  CHECK(lines[3] == "FAIL 1 of 2 images with 1 parts of type 1");
  run = e2e::run({binPath("picksight-vision"), "test-run", "--models", cell.vision.data_dir,
                  "--images", path, "--expect", "1"});
  CHECK(run.exit_code == 1);
  fs::remove(path + "/000002.png");
  run = e2e::run({binPath("picksight-vision"), "test-run", "--models", cell.vision.data_dir,
                  "--images", path, "--expect", "1", "--type", "1"});
  CHECK(run.exit_code == 0);
  CHECK_THAT(run.out, Catch::EndsWith("PASS 1 of 1 images with 1 parts of type 1\n"));
  run = e2e::run({binPath("picksight-vision"), "test-run", "--models", cell.vision.data_dir,
                  "--images", path});
  CHECK(run.exit_code == 2);

  // The exported frame, served by a dir: camera to another vision app
  // with the same model, is found where the first one found it.
  fs::remove_all(path);
  REQUIRE(cell.ask("FILMSTRIP EXPORT run2 1").rfind("OK 1 ", 0) == 0);  // the newest: the bar
  VideoServerProcess replay_server{
      {"--source", "cam1=dir:" + cell.strip() + "/exports/run2", "--mode", "trigger"}};
  VisionProcess other(replay_server, "cam1");
  LineClient robot = other.connect();
  auto learned = robot.request("LEARN 1 bar", 20s);
  REQUIRE(learned);
  CHECK_THAT(*learned, Catch::StartsWith("OK 1 bar "));
  REQUIRE(cell.ask("LEARN 1 bar").rfind("OK 1 bar ", 0) == 0);
  auto located = robot.request("LOCATE 1", 20s);
  REQUIRE(located);
  CHECK(*located == cell.ask("REPLAY 2"));
}
