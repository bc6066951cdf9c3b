// JOB against a real video server and vision app over TCP: two jobs whose
// LOCATE ALL answers differ in every part of a job (models, vision
// settings, calibration), saved and switched; LOCATEs racing JOB LOADs
// each answer as exactly one of the two jobs; damaged job files (cut
// short, a checksum that does not match, not JSON, a model missing)
// refused by name with the cell answering exactly as before; names
// checked; the read-only port; export and import as one file.
#include <catch2/catch.hpp>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "../vision/drawn_parts.hpp"
#include "cell_fixture.hpp"
#include "file_text.hpp"
#include "picksight/jobs/job_file.hpp"
#include "picksight/store/model_history.hpp"
#include "scene_file.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::tool_support;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {
// A plate with a hole (about 5500 px) and a bar without (8000 px).
const synthetic::Shape kPlate{{test::rectLoop(100, 60), test::circleLoop(12, {20, 0})}};
const synthetic::Shape kBar{{test::rectLoop(200, 40)}};

cv::Mat scene() {
  return test::drawParts(
      640, 480,
      {{kPlate, 160, 120, 0}, {kPlate, 470, 130, 30}, {kBar, 170, 360, 10}, {kBar, 460, 350, -20}},
      7);
}

// Half a millimetre per pixel: LOCATE replies in vision-mm.
const std::string kCalibration =
    "format_version: 2\nnext_id: 1\npoints: []\nscale:\n  mm_per_px_x: 0.5\n  mm_per_px_y: "
    "0.5\n  skew_deg: 0\n";

// A file camera in trigger mode, a vision app with a set-up port beside a
// read-only robot port, and two jobs:
//   bars:   the bar as type 2, min_area 7000 (the plates are specks), the
//           calibration above (vision-mm);
//   plates: the plate as type 1, the default settings, no calibration.
// Any half of one with half of the other answers LOCATE ALL otherwise:
// plates under min_area 7000 find nothing, and either model under the
// other job's calibration replies in the other unit.
struct JobCell {
  SceneFile scene_file{scene()};
  std::string data_dir = scene_file.dir + "/data";
  VideoServerProcess server{{"--source", "cam0=file:" + scene_file.path, "--mode", "trigger"}};
  std::unique_ptr<VisionProcess> vision;
  std::unique_ptr<LineClient> setup;
  std::unique_ptr<LineClient> robot;
  std::string bars_reply;
  std::string plates_reply;

  JobCell() {
    fs::create_directories(data_dir);
    test::writeFileText(data_dir + "/calibration.yaml", kCalibration);
    vision = std::make_unique<VisionProcess>(
        server, "cam0", data_dir,
        std::vector<std::string>{"--robot-read-only", "--setup-port", "0"});
    REQUIRE(vision->setup_port != 0);
    robot = std::make_unique<LineClient>(vision->connect());
    auto s = LineClient::connect("127.0.0.1", vision->setup_port, 5s);
    REQUIRE(s);
    setup = std::make_unique<LineClient>(std::move(*s));

    REQUIRE(ask("LEARN 2 bar AT 60 320 220 80").rfind("OK 2 bar ", 0) == 0);
    REQUIRE(ask("VISION min_area 7000").rfind("OK ", 0) == 0);
    REQUIRE(ask("JOB SAVE bars").rfind("OK bars 1 1 ", 0) == 0);
    bars_reply = ask("LOCATE ALL");

    REQUIRE(ask("FORGET 2") == "OK");
    REQUIRE(ask("CLEARCAL").rfind("OK", 0) == 0);
    REQUIRE(ask("VISION min_area auto").rfind("OK ", 0) == 0);
    REQUIRE(ask("LEARN 1 plate AT 100 80 120 80").rfind("OK 1 plate ", 0) == 0);
    REQUIRE(ask("JOB SAVE plates").rfind("OK plates 1 0 ", 0) == 0);
    plates_reply = ask("LOCATE ALL");
  }
  std::string ask(const std::string& request) { return askOn(*setup, request); }
  static std::string askOn(LineClient& client, const std::string& request) {
    auto reply = client.request(request, 30s);
    REQUIRE(reply);
    return *reply;
  }
  std::string jobFile(const std::string& name) const { return data_dir + "/jobs/" + name + ".job"; }
  // Everything a robot could ask about the cell's state.
  std::vector<std::string> state() {
    return {ask("LOCATE ALL"),   ask("MODELS"),       ask("VISION"), ask("STATUS").substr(0, 60),
            ask("GRASP 1 LIST"), ask("GRASP 2 LIST"), ask("JOB")};
  }
};

}  // namespace

TEST_CASE("two jobs answer LOCATE ALL each in its own way, and a switch brings each back",
          "[e2e][jobs]") {
  JobCell cell;
  INFO(cell.bars_reply);
  INFO(cell.plates_reply);
  // Two bars of type 2 in mm; two plates of type 1 in pixels.
  REQUIRE(cell.bars_reply.rfind("OK 2 2 ", 0) == 0);
  REQUIRE(cell.plates_reply.rfind("OK 2 1 ", 0) == 0);
  CHECK(cell.ask("STATUS").find("frame=vision-px") != std::string::npos);

  CHECK(cell.ask("JOB LOAD bars") == "OK bars 1 1 1");
  CHECK(cell.ask("LOCATE ALL") == cell.bars_reply);
  CHECK(cell.ask("STATUS").find("frame=vision-mm") != std::string::npos);
  CHECK(cell.ask("VISION").find("min_area=7000") != std::string::npos);
  CHECK(cell.ask("JOB") == "OK bars");
  // The teach image came back with the model.
  CHECK(fs::exists(cell.data_dir + "/models/type_2.png"));
  CHECK_FALSE(fs::exists(cell.data_dir + "/models/type_1.yaml"));

  CHECK(cell.ask("JOB LOAD plates") == "OK plates 1 0 1");
  CHECK(cell.ask("LOCATE ALL") == cell.plates_reply);
  CHECK(cell.ask("STATUS").find("frame=vision-px") != std::string::npos);
  CHECK(cell.ask("JOB LIST") == "OK 2 bars plates");
  // The previous job's undo history went with its models.
  CHECK(cell.ask("UNDO").rfind("ERROR 37", 0) == 0);
}

TEST_CASE("LOCATEs racing JOB LOADs each see exactly one job", "[e2e][jobs]") {
  JobCell cell;
  REQUIRE(cell.bars_reply != cell.plates_reply);
  std::atomic<bool> done{false};
  std::atomic<int> bars{0}, plates{0};
  std::vector<std::string> mixed;
  std::mutex mixed_mutex;
  std::vector<std::thread> robots;
  for (int i = 0; i < 2; ++i) {
    robots.emplace_back([&] {
      LineClient robot = cell.vision->connect();
      while (!done) {
        auto reply = robot.request("LOCATE ALL", 30s);
        if (!reply) continue;
        if (*reply == cell.bars_reply) {
          ++bars;
        } else if (*reply == cell.plates_reply) {
          ++plates;
        } else {
          std::lock_guard<std::mutex> lock(mixed_mutex);
          mixed.push_back(*reply);
        }
      }
    });
  }
  for (int i = 0; i < 15; ++i) {
    CHECK(cell.ask("JOB LOAD bars").rfind("OK bars ", 0) == 0);
    CHECK(cell.ask("JOB LOAD plates").rfind("OK plates ", 0) == 0);
  }
  done = true;
  for (auto& t : robots) t.join();
  WARN("LOCATE ALL answered as bars " << bars << " times, as plates " << plates << " times");
  std::string seen;
  for (const auto& reply : mixed) seen += "\n" + reply;
  INFO("half of one job, half of another:" << seen);
  CHECK(mixed.empty());
  CHECK(bars + plates > 0);
}

TEST_CASE("a damaged job file is refused by name and changes nothing", "[e2e][jobs]") {
  JobCell cell;
  REQUIRE(cell.ask("JOB LOAD plates").rfind("OK", 0) == 0);
  const auto before = cell.state();
  const auto files = [&] {
    std::vector<std::string> out;
    // The filmstrip is left out: it records the LOCATEs of state() by
    // itself, on a writer thread at idle priority that a busy machine
    // holds back for seconds (a half-written frame seen in CI). So are the
    // models a JOB LOAD replaced (`models.job-replaced.<n>`), which a
    // cleaner removes after the reply (seen half removed in CI): not even
    // entered, as they may go while they are listed.
    for (auto it = fs::recursive_directory_iterator(cell.data_dir);
         it != fs::recursive_directory_iterator(); ++it) {
      const std::string top = fs::relative(it->path(), cell.data_dir).begin()->string();
      if (top == "filmstrip" || top.find(".job-replaced.") != std::string::npos) {
        if (it->is_directory()) it.disable_recursion_pending();
        continue;
      }
      if (it->is_regular_file())
        out.push_back(it->path().string() + "=" + test::readFileText(it->path()));
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  const std::string good = test::readFileText(cell.jobFile("bars"));
  // The content's checksum made again over everything but the files'
  // bytes (which carry their own), as the job file keeps it.
  const auto reChecksummed = [](nlohmann::json j) {
    nlohmann::json manifest = j["content"];
    for (const char* key : {"vision_json", "calibration_yaml"}) manifest.erase(key);
    for (auto& m : manifest["models"]) {
      m.erase("yaml");
      m.erase("teach_png");
    }
    j["content_sha256"] = store::sha256Hex(manifest.dump());
    return j.dump();
  };
  struct Damage {
    std::string what;
    std::string text;
    std::string says;
  };
  auto parsed = nlohmann::json::parse(good);
  auto edited = parsed;
  {
    std::string yaml = edited["content"]["models"][0]["yaml"];
    yaml[yaml.size() / 2] ^= 1;
    edited["content"]["models"][0]["yaml"] = yaml;
  }
  auto retyped = parsed;
  retyped["content"]["models"][0]["type"] = 3;
  auto missing = parsed;
  missing["content"]["models"] = nlohmann::json::array();
  auto bad_settings = parsed;
  bad_settings["content"]["vision_json"] = "{\"format\":\"nonsense\"}";
  bad_settings["content"]["vision_json_sha256"] = store::sha256Hex("{\"format\":\"nonsense\"}");
  const std::vector<Damage> damages = {
      {"cut short", good.substr(0, good.size() / 2), "not JSON"},
      {"a byte of a model file changed", edited.dump(),
       "type 2's model file: checksum does not match"},
      {"a type number changed", retyped.dump(), "content checksum does not match"},
      {"a type number changed, the checksum made again", reChecksummed(retyped),
       "type 3's model file holds type 2"},
      {"not JSON", "PK\x03\x04 zip file", "not JSON"},
      {"a model missing", reChecksummed(missing), "model missing: 0 of 1"},
      {"vision settings that do not read", reChecksummed(bad_settings), "its vision settings"},
  };
  const auto on_disk = files();
  for (const auto& d : damages) {
    INFO(d.what);
    test::writeFileText(cell.jobFile("broken"), d.text);
    const std::string reply = cell.ask("JOB LOAD broken");
    CHECK(reply.rfind("ERROR 51 ", 0) == 0);
    CHECK(reply.find(cell.jobFile("broken")) != std::string::npos);
    CHECK(reply.find(d.says) != std::string::npos);
    CHECK(cell.state() == before);
    fs::remove(cell.jobFile("broken"));
    CHECK(files() == on_disk);
  }
  CHECK(cell.ask("JOB LOAD nothing").rfind("ERROR 50 ", 0) == 0);
  CHECK(cell.state() == before);
  // A job loaded before (kept parsed) whose file is damaged since: the
  // file is what counts.
  test::writeFileText(cell.jobFile("plates"), good.substr(0, good.size() / 3));
  const std::string reply = cell.ask("JOB LOAD plates");
  CHECK(reply.rfind("ERROR 51 ", 0) == 0);
  CHECK(reply.find(cell.jobFile("plates")) != std::string::npos);
  CHECK(cell.state() == before);
}

TEST_CASE("job names are checked, changes refused on a read-only port", "[e2e][jobs]") {
  JobCell cell;
  for (const std::string& bad :
       std::vector<std::string>{"../x", ".hidden", "a/b", std::string(65, 'a'), "name*"}) {
    INFO(bad);
    CHECK(cell.ask("JOB SAVE " + bad).rfind("ERROR 54 ", 0) == 0);
  }
  CHECK(cell.ask("JOB SAVE").rfind("ERROR 11 ", 0) == 0);
  CHECK(cell.ask("JOB FLY plates").rfind("ERROR 11 ", 0) == 0);
  for (const std::string& change : std::vector<std::string>{
           "JOB SAVE x", "JOB LOAD bars", "JOB DELETE bars", "JOB IMPORT x 0 4 AAAA"}) {
    INFO(change);
    CHECK(JobCell::askOn(*cell.robot, change).rfind("ERROR 17 ", 0) == 0);
  }
  CHECK(JobCell::askOn(*cell.robot, "JOB LIST") == "OK 2 bars plates");
  CHECK(JobCell::askOn(*cell.robot, "JOB") == "OK plates");
  CHECK(cell.ask("JOB DELETE bars") == "OK bars");
  CHECK(cell.ask("JOB DELETE bars").rfind("ERROR 50 ", 0) == 0);
  CHECK(cell.ask("JOB LIST") == "OK 1 plates");
}

TEST_CASE("a job exported in pieces and imported under another name loads as the original",
          "[e2e][jobs]") {
  JobCell cell;
  std::string file;
  for (;;) {
    const std::string reply = cell.ask("JOB EXPORT bars " + std::to_string(file.size()));
    std::istringstream fields(reply);
    std::string ok, piece;
    size_t total = 0, offset = 0;
    fields >> ok >> total >> offset >> piece;
    REQUIRE(ok == "OK");
    REQUIRE(offset == file.size());
    auto bytes = jobs::base64Decode(piece);
    REQUIRE(bytes);
    file += *bytes;
    if (file.size() >= total) break;
  }
  CHECK(file == test::readFileText(cell.jobFile("bars")));
  std::string last;
  for (size_t at = 0; at < file.size(); at += 2880) {
    const std::string piece = file.substr(at, 2880);
    last = cell.ask("JOB IMPORT copy " + std::to_string(at) + " " + std::to_string(file.size()) +
                    " " + jobs::base64Encode(piece));
    if (at + piece.size() < file.size())
      REQUIRE(last ==
              "MORE " + std::to_string(at + piece.size()) + " " + std::to_string(file.size()));
  }
  CHECK(last == "OK copy 1 1 1 " + std::to_string(file.size()));
  CHECK(cell.ask("JOB LOAD copy") == "OK copy 1 1 1");
  CHECK(cell.ask("LOCATE ALL") == cell.bars_reply);
  // A piece out of order drops the import.
  CHECK(cell.ask("JOB IMPORT other 8 100 AAAA").rfind("ERROR 51 ", 0) == 0);
  CHECK(cell.ask("JOB LIST") == "OK 3 bars copy plates");
}
