// VISION against a real video server and vision app over TCP: light parts on
// a dark table, where the default polarity takes the table for the part,
// fixed without a restart; the settings kept in vision.json across a
// restart, the command line winning over it; bad requests refused naming
// the key and changing nothing; the read-only port; a damaged file refused
// by name until VISION RESET; the models a change leaves taught under other
// settings named in the reply; LOCATEs racing changes of two keys each see
// one whole setting, and publish it.
#include <catch2/catch.hpp>

#include <opencv2/imgproc.hpp>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <zmq.hpp>

#include "cell_fixture.hpp"
#include "file_text.hpp"
#include "results.pb.h"
#include "scene_file.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::tool_support;
using namespace std::chrono_literals;

namespace {

// Six light discs (radius 40 px) on a dark table that stops 30 px short of
// the frame's edges, inside a light rim: with dark parts on a light
// surface (the default), the table is one region that holds the discs as
// its six holes and touches no border, so LOCATE takes it for a part.
cv::Mat lightOnDarkTable() {
  cv::Mat image(480, 640, CV_8UC1, cv::Scalar(200));
  cv::rectangle(image, cv::Rect(30, 30, 580, 420), cv::Scalar(50), cv::FILLED);
  for (const cv::Point c : {cv::Point(150, 150), cv::Point(320, 150), cv::Point(490, 150),
                            cv::Point(150, 330), cv::Point(320, 330), cv::Point(490, 330)})
    cv::circle(image, c, 40, cv::Scalar(210), cv::FILLED, cv::LINE_AA);
  cv::Mat noise(image.size(), CV_8UC1);
  cv::randn(noise, 0, 3);
  cv::add(image, noise, image);
  return image;
}

// The count of a LOCATE reply "OK <n> ..."; REQUIREs the OK.
int located(const std::string& reply) {
  INFO(reply);
  REQUIRE(reply.rfind("OK ", 0) == 0);
  return std::stoi(reply.substr(3));
}

// The area (sensor pixels) of BLOBS' first (largest) region, 0 when none.
double largestBlobArea(const std::string& reply) {
  INFO(reply);
  REQUIRE(reply.rfind("OK ", 0) == 0);
  std::istringstream fields(reply.substr(3));
  int count = 0;
  fields >> count;
  if (count == 0) return 0;
  double x = 0, y = 0, angle = 0, area = 0;
  fields >> x >> y >> angle >> area;
  return area;
}

const std::string kDefaults =
    "OK polarity=dark threshold=adaptive level=128 window=0 min_area=auto min_hole_area=0.000";
const std::string kLight =
    "OK polarity=light threshold=adaptive level=128 window=0 min_area=auto min_hole_area=0.000";

// A file camera in trigger mode showing the table, a vision app on it whose
// data directory outlives it (restarts), with a set-up port beside a
// read-only robot port.
struct TableCell {
  SceneFile scene{lightOnDarkTable()};
  std::string data_dir = scene.dir + "/data";
  std::string settings_file = data_dir + "/vision.json";
  VideoServerProcess server{{"--source", "cam0=file:" + scene.path, "--mode", "trigger"}};
  std::unique_ptr<VisionProcess> vision;
  std::unique_ptr<LineClient> setup;
  std::unique_ptr<LineClient> robot;

  explicit TableCell(const std::vector<std::string>& args = {}) {
    std::filesystem::create_directories(data_dir);
    restart(args);
  }
  void restart(const std::vector<std::string>& args = {}) {
    setup.reset();
    robot.reset();
    vision.reset();
    std::vector<std::string> all = {"--robot-read-only", "--setup-port", "0"};
    all.insert(all.end(), args.begin(), args.end());
    vision = std::make_unique<VisionProcess>(server, "cam0", data_dir, all);
    REQUIRE(vision->setup_port != 0);
    robot = std::make_unique<LineClient>(vision->connect());
    auto s = LineClient::connect("127.0.0.1", vision->setup_port, 5s);
    REQUIRE(s);
    setup = std::make_unique<LineClient>(std::move(*s));
  }
  static std::string askOn(LineClient& client, const std::string& request) {
    auto reply = client.request(request, 20s);
    REQUIRE(reply);
    return *reply;
  }
  std::string ask(const std::string& request) { return askOn(*setup, request); }
  std::string askRobot(const std::string& request) { return askOn(*robot, request); }
};

}  // namespace

TEST_CASE("VISION polarity light finds light parts on a dark table without a restart",
          "[vision_app][vision_settings][e2e]") {
  TableCell cell;
  CHECK(cell.ask("VISION") == kDefaults);
  CHECK_FALSE(std::filesystem::exists(cell.settings_file));
  // Dark parts on a light surface: the table is the one "part", holding the
  // six discs as holes, most of the frame.
  CHECK(located(cell.ask("LOCATE ALL")) == 1);
  CHECK(largestBlobArea(cell.ask("BLOBS")) > 0.5 * 640 * 480);
  // VISION says so: the table is 69 % of the last frame.
  const std::string hint =
      " ; hint: 69 % of the last frame is taken for part, more than the surface: parts lighter "
      "than their surface need VISION polarity light";
  CHECK(cell.ask("VISION") == kDefaults + hint);

  // The read-only robot port reads the settings and refuses a change.
  CHECK(cell.askRobot("VISION") == kDefaults + hint);
  CHECK_THAT(cell.askRobot("VISION polarity light"), Catch::StartsWith("ERROR 17 "));
  CHECK_THAT(cell.askRobot("VISION RESET"), Catch::StartsWith("ERROR 17 "));
  CHECK(cell.ask("VISION") == kDefaults + hint);

  // The next LOCATE after the change sees the discs, on either port.
  CHECK(cell.ask("VISION polarity light") == kLight);
  CHECK(located(cell.ask("LOCATE ALL")) == 6);
  CHECK(located(cell.askRobot("LOCATE ALL")) == 6);
  CHECK(largestBlobArea(cell.ask("BLOBS")) < 0.05 * 640 * 480);
  const std::string file = test::readFileText(cell.settings_file);
  CHECK_THAT(file, Catch::Contains("\"format\": \"picksight-vision-settings\""));
  CHECK_THAT(file, Catch::Contains("\"polarity\": \"light\""));

  // The offline tool on the same data dir reads them too, its own options
  // winning.
  const auto offline = [&](const std::vector<std::string>& args) {
    std::vector<std::string> argv = {binPath("picksight-vision"), "locate", "--data-dir",
                                     cell.data_dir};
    argv.insert(argv.end(), args.begin(), args.end());
    argv.push_back(cell.scene.path);
    return run(argv);
  };
  const auto light_offline = offline({});
  CHECK(light_offline.exit_code == 0);
  CHECK(located(light_offline.out) == 6);
  const auto dark_offline = offline({"--polarity", "dark"});
  CHECK(dark_offline.exit_code == 0);
  CHECK(located(dark_offline.out) == 1);

  // Stored: a restarted app has it. Several keys at once, in any case.
  cell.restart();
  CHECK(cell.ask("VISION") == kLight);
  CHECK(located(cell.ask("LOCATE ALL")) == 6);
  CHECK(cell.ask("VISION THRESHOLD fixed Level 120 window 64 min_area 300 min_hole_area 12.5") ==
        "OK polarity=light threshold=fixed level=120 window=64 min_area=300.000 "
        "min_hole_area=12.500");
  CHECK(located(cell.ask("LOCATE ALL")) == 6);
  // A minimum region area above a disc's (5000 px) leaves none.
  CHECK(cell.ask("VISION min_area 6000 threshold adaptive").rfind("OK ", 0) == 0);
  CHECK(located(cell.ask("LOCATE ALL")) == 0);
  CHECK(cell.ask("VISION min_area auto window 0 level 128 min_hole_area 0") == kLight);
  CHECK(located(cell.ask("LOCATE ALL")) == 6);
}

TEST_CASE("VISION refuses a bad request naming the key and changes nothing",
          "[vision_app][vision_settings][e2e]") {
  TableCell cell;
  REQUIRE(cell.ask("VISION polarity light") == kLight);
  const std::string file = test::readFileText(cell.settings_file);
  struct Bad {
    const char* request;
    const char* says;
  };
  const Bad bad[] = {
      {"VISION polarity grey", "polarity must be dark (dark parts on a light surface) or light"},
      {"VISION threshold mean", "threshold must be adaptive, otsu or fixed"},
      {"VISION level 256", "level must be an integer grey level in [0, 255]"},
      {"VISION level -1", "level must be an integer grey level in [0, 255]"},
      {"VISION level 12.5", "level must be an integer grey level in [0, 255]"},
      {"VISION window 7",
       "window must be 0 (a sixth of the smaller image side) or an integer "
       "in [8, 16384] pixels, got '7'"},
      {"VISION window 16385", "window must be 0"},
      {"VISION min_area 0", "min_area must be auto (50 px"},
      {"VISION min_area nan", "min_area must be auto"},
      {"VISION min_area 1e10", "min_area must be auto"},
      {"VISION min_hole_area -1", "min_hole_area must be a number in [0, 1e9] sensor pixels"},
      {"VISION min_hole_area inf", "min_hole_area must be a number in [0, 1e9]"},
      {"VISION speed 3",
       "no key 'speed' (keys: polarity, threshold, level, window, min_area, "
       "min_hole_area)"},
      {"VISION level 100 LEVEL 90", "level given twice"},
      // One good pair and one bad: neither applies.
      {"VISION polarity dark level 999", "level must be"},
      {"VISION polarity", "usage: VISION [RESET | <key> <value> [<key> <value>]...]"},
      {"VISION RESET now", "no key 'RESET'"},
  };
  for (const auto& b : bad) {
    INFO(b.request);
    const std::string reply = cell.ask(b.request);
    CHECK_THAT(reply, Catch::StartsWith("ERROR 11 "));
    CHECK_THAT(reply, Catch::Contains(b.says));
  }
  // A very long value is echoed cut short.
  CHECK_THAT(cell.ask("VISION polarity " + std::string(3000, 'x')),
             Catch::EndsWith("got '" + std::string(40, 'x') + "...'"));
  CHECK(cell.ask("VISION") == kLight);
  CHECK(test::readFileText(cell.settings_file) == file);
  CHECK(located(cell.ask("LOCATE ALL")) == 6);
}

TEST_CASE("Settings given on the command line win over vision.json at start",
          "[vision_app][vision_settings][e2e]") {
  TableCell cell;
  REQUIRE(cell.ask("VISION polarity light min_hole_area 20") ==
          "OK polarity=light threshold=adaptive level=128 window=0 min_area=auto "
          "min_hole_area=20.000");
  cell.restart({"--polarity", "dark", "--min-area", "80"});
  // polarity and min_area from the command line, min_hole_area from the file.
  CHECK(cell.ask("VISION") ==
        "OK polarity=dark threshold=adaptive level=128 window=0 min_area=80.000 "
        "min_hole_area=20.000");
  CHECK(located(cell.ask("LOCATE ALL")) == 1);
  // Until a change, which is stored whole.
  CHECK(cell.ask("VISION polarity light").rfind("OK polarity=light ", 0) == 0);
  CHECK(located(cell.ask("LOCATE ALL")) == 6);
  cell.restart();
  CHECK(cell.ask("VISION") ==
        "OK polarity=light threshold=adaptive level=128 window=0 min_area=80.000 "
        "min_hole_area=20.000");
}

TEST_CASE("A damaged vision.json is refused by name until it is repaired or VISION RESET",
          "[vision_app][vision_settings][e2e]") {
  TableCell cell;
  REQUIRE(cell.ask("VISION polarity light") == kLight);
  const std::string good = test::readFileText(cell.settings_file);
  const std::string damaged[] = {
      "{\"format\": \"picksight-vision-settings\", \"version\": 1, \"polarity\": \"light\"",
      "{\"format\": \"picksight-vision-settings\", \"version\": 1, \"polarity\": \"sideways\"}",
      "{\"format\": \"picksight-vision-settings\", \"version\": 1, \"polarty\": \"light\"}",
      "{\"format\": \"something else\", \"version\": 1}",
      "[1, 2]",
      std::string(70000, ' ') + "{}",
  };
  const char* const says[] = {"not JSON",          "polarity must be dark",
                              "no key 'polarty'",  "format is not 'picksight-vision-settings'",
                              "not a JSON object", "larger than 64 KiB"};
  for (size_t i = 0; i < std::size(damaged); ++i) {
    INFO(damaged[i].substr(0, 100));
    cell.restart();  // the app running writes nothing now: the file is ours
    test::writeFileText(cell.settings_file, damaged[i]);
    cell.restart();
    // Not silently replaced by defaults: every request that binarizes is
    // refused naming the file, and so is a change, which would overwrite it.
    const std::string reply = cell.ask("VISION");
    CHECK_THAT(reply, Catch::StartsWith(kDefaults + " ; error: the settings file is damaged (" +
                                        cell.settings_file + ": "));
    CHECK_THAT(reply, Catch::Contains(says[i]));
    for (const char* request : {"LOCATE ALL", "BLOBS", "LEARN 1 disc", "VISION polarity light"}) {
      INFO(request);
      const std::string refused = cell.ask(request);
      CHECK_THAT(refused, Catch::StartsWith("ERROR 48 the vision settings file is damaged (" +
                                            cell.settings_file));
      CHECK_THAT(refused, Catch::EndsWith("repair it and restart, or VISION RESET"));
    }
    CHECK(test::readFileText(cell.settings_file) == damaged[i]);
    // The offline tool on that data dir refuses too, whatever it is given.
    const auto offline = run({binPath("picksight-vision"), "locate", "--data-dir", cell.data_dir,
                              "--polarity", "light", cell.scene.path});
    CHECK(offline.exit_code == 2);
    CHECK(offline.out.empty());
  }
  // A file that cannot be replaced (here a directory in its place): VISION
  // RESET fails with ERROR 49 and lifts nothing.
  cell.restart();
  std::filesystem::remove(cell.settings_file);
  std::filesystem::create_directories(cell.settings_file + "/in-the-way");
  cell.restart();
  CHECK_THAT(cell.ask("VISION RESET"),
             Catch::StartsWith("ERROR 49 cannot write " + cell.settings_file + ": "));
  CHECK_THAT(cell.ask("LOCATE ALL"), Catch::StartsWith("ERROR 48 "));
  CHECK_THAT(cell.ask("VISION polarity light"), Catch::StartsWith("ERROR 48 "));
  std::filesystem::remove_all(cell.settings_file);

  // A bad value is refused even where the command line overrides it.
  test::writeFileText(cell.settings_file, damaged[1]);
  cell.restart({"--polarity", "light"});
  CHECK_THAT(cell.ask("LOCATE ALL"), Catch::StartsWith("ERROR 48 "));
  // Repaired by hand: in force at the next start.
  test::writeFileText(cell.settings_file, good);
  cell.restart();
  CHECK(cell.ask("VISION") == kLight);
  CHECK(located(cell.ask("LOCATE ALL")) == 6);
  // Or replaced, on purpose, by the settings in use.
  test::writeFileText(cell.settings_file, "garbage");
  cell.restart({"--polarity", "light"});
  CHECK_THAT(cell.ask("LOCATE ALL"), Catch::StartsWith("ERROR 48 "));
  CHECK(cell.ask("VISION RESET") == kLight);
  CHECK(located(cell.ask("LOCATE ALL")) == 6);
  CHECK(cell.ask("VISION") == kLight);
  CHECK_THAT(test::readFileText(cell.settings_file), Catch::Contains("\"polarity\": \"light\""));
}

TEST_CASE("A VISION change names the models it leaves taught under other settings",
          "[vision_app][vision_settings][e2e]") {
  TableCell cell({"--polarity", "light"});
  // One disc alone in the frame to teach it.
  cv::Mat one(480, 640, CV_8UC1, cv::Scalar(50));
  cv::circle(one, {320, 240}, 40, cv::Scalar(210), cv::FILLED, cv::LINE_AA);
  cell.scene.show(one);
  REQUIRE(cell.ask("LEARN 1 disc").rfind("OK 1 disc ", 0) == 0);
  cell.scene.show(lightOnDarkTable());
  CHECK(located(cell.ask("LOCATE 1")) == 6);
  // The level of a fixed threshold: the outline stays, nothing to re-teach.
  CHECK(cell.ask("VISION threshold fixed level 130") ==
        "OK polarity=light threshold=fixed level=130 window=0 min_area=auto min_hole_area=0.000");
  CHECK(located(cell.ask("LOCATE 1")) == 6);
  // The model counts holes from the area it was taught with.
  CHECK(cell.ask("VISION min_hole_area 150") ==
        "OK polarity=light threshold=fixed level=130 window=0 min_area=auto "
        "min_hole_area=150.000 ; re-teach: 1 (disc) counts holes from 0.000 px");
  // The other polarity makes the table the part: the disc model no longer
  // fits anything there.
  CHECK(cell.ask("VISION polarity dark") ==
        "OK polarity=dark threshold=fixed level=130 window=0 min_area=auto "
        "min_hole_area=150.000 ; re-teach: 1 (disc) taught as light on its surface ; hint: 69 % "
        "of the last frame is taken for part, more than the surface: parts lighter than their "
        "surface need VISION polarity light");
  CHECK(located(cell.ask("LOCATE 1")) == 0);
  // Back to the settings it was taught under: nothing to re-teach.
  CHECK(cell.ask("VISION polarity light threshold adaptive min_hole_area 0") ==
        "OK polarity=light threshold=adaptive level=130 window=0 min_area=auto "
        "min_hole_area=0.000");
  CHECK(located(cell.ask("LOCATE 1")) == 6);
}

TEST_CASE("Each LOCATE runs with one whole VISION change and publishes the settings it ran with",
          "[vision_app][vision_settings][e2e][results]") {
  TableCell cell;
  zmq::context_t context;
  zmq::socket_t results(context, zmq::socket_type::sub);
  results.set(zmq::sockopt::subscribe, "cam0");
  results.set(zmq::sockopt::linger, 0);
  results.set(zmq::sockopt::rcvtimeo, 300);
  results.connect(cell.vision->results_endpoint);
  const auto next = [&]() -> std::optional<proto::VisionResult> {
    zmq::message_t topic, body;
    if (!results.recv(topic)) return std::nullopt;
    REQUIRE(results.recv(body));
    proto::VisionResult r;
    REQUIRE(r.ParseFromArray(body.data(), static_cast<int>(body.size())));
    return r;
  };
  // A SUB joins a moment after it connects: LOCATE until one arrives.
  bool joined = false;
  for (int i = 0; i < 100 && !joined; ++i) {
    cell.askRobot("LOCATE ALL");
    joined = next().has_value();
  }
  REQUIRE(joined);
  while (next()) {
  }

  // Two settings, two keys each: dark parts and every region (the table: 1
  // part), or light parts and none under 6000 px (no disc: 0 parts). Half of
  // either change (light parts and every region) would find the 6 discs.
  const char* const a = "VISION polarity dark min_area auto";
  const char* const b = "VISION polarity light min_area 6000";
  std::atomic<bool> done{false};
  std::atomic<int> changes{0};
  std::thread changer([&] {
    for (int i = 0; !done; ++i) {
      if (cell.ask(i % 2 == 0 ? b : a).rfind("OK ", 0) == 0) ++changes;
    }
  });
  constexpr int kLocates = 60;
  std::vector<std::string> replies;
  for (int i = 0; i < kLocates; ++i) replies.push_back(cell.askRobot("LOCATE ALL"));
  done = true;
  changer.join();
  CHECK(changes > 0);
  int dark = 0;
  int light = 0;
  for (const auto& reply : replies) {
    INFO(reply);
    const int n = located(reply);
    CHECK((n == 0 || n == 1));
    (n == 1 ? dark : light) += 1;
  }
  INFO("dark " << dark << ", light " << light << ", changes " << changes);
  // Each LOCATE's record carries the settings that LOCATE ran with. (A
  // record made with the settings read after the LOCATE was caught by 2 of
  // 3 runs here; a change applied one key at a time, by 3 of 3.)
  // The publisher may drop a record when it falls behind (it keeps the
  // newest for a viewer, and the changes for the audit trail; the likely
  // cause of this test's one failure in CI, whose failing check was cut
  // from the log), but never reorders them: the records are the replies in
  // order, some left out.
  size_t at = 0;
  int seen = 0;
  int seen_table = 0;
  for (auto r = next(); r && seen < kLocates; r = next()) {
    if (r->request() != "LOCATE") continue;
    INFO(r->reply());
    while (at < replies.size() && replies[at] != r->reply()) ++at;
    CHECK(at < replies.size());
    ++at;
    const bool found_table = located(r->reply()) == 1;
    CHECK(r->binarize().dark_parts() == found_table);
    CHECK(r->binarize().min_region_area() == (found_table ? 50.0 : 6000.0));
    ++seen;
    seen_table += found_table ? 1 : 0;
  }
  INFO("records " << seen << ", of the table " << seen_table);
  CHECK(seen > 0);
}

TEST_CASE("Coins on a dark table: VISION hints at polarity light, then LOCATE finds all 24",
          "[vision_app][vision_settings][e2e]") {
  // The photograph of the issue (tests/data/scenes/coins.png, scikit-image):
  // 24 light coins on a darker, unevenly lit table.
  PhotographCell cell("coins.png");
  const auto ask = [&](const std::string& request) { return cell.ask(request); };
  // Dark parts: pieces of the table, not a coin.
  CHECK(located(ask("LOCATE ALL")) != 24);
  const std::string before = ask("VISION");
  CHECK_THAT(before, Catch::StartsWith(kDefaults + " ; hint: "));
  CHECK_THAT(before, Catch::EndsWith(" of the last frame is taken for part, more than the "
                                     "surface: parts lighter than their surface need VISION "
                                     "polarity light"));
  CHECK(ask("VISION polarity light") == kLight);
  CHECK(located(ask("LOCATE ALL")) == 24);
  CHECK(ask("VISION") == kLight);
}
