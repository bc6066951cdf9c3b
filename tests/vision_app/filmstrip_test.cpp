// The filmstrip library: entries written off the request thread with their
// frame and sidecar, the bounds (successes and failures apart, failures
// kept), the full queue dropping successes first, damaged sidecars reported
// and skipped, the export a dir: camera serves, and the robot codes.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <future>
#include <mutex>

#include "picksight/codecs/codecs.hpp"

#include "picksight/common/atomic_file.hpp"
#include "picksight/filmstrip/filmstrip.hpp"
#include "picksight/protocol/robot_errors.hpp"
#include "temp_dir.hpp"

using namespace picksight;
using namespace picksight::filmstrip;
namespace fs = std::filesystem;

namespace {

// A LOCATE that answered `reply`, on a frame with a grey level of `level`,
// with the cell's `geometry` when given.
Take locateTake(const std::string& reply, int level = 100,
                std::optional<store::CellGeometry> geometry = std::nullopt) {
  auto record = std::make_shared<results::RequestRecord>();
  record->geometry = std::move(geometry);
  record->request = "LOCATE";
  record->request_line = "LOCATE 1";
  record->reply = reply;
  record->asked_type = 1;
  auto frame = std::make_shared<Frame>(
      frameFromImage(cv::Mat(48, 64, CV_8UC1, cv::Scalar(level)), "cam0", 7));
  frame->mapping.roi_x = 10;
  frame->mapping.scale_x = 0.5;
  return {record, frame, "LOCATE", 0};
}

FilmstripOptions in(const std::string& dir) {
  FilmstripOptions options;
  options.dir = dir;
  options.success_interval = std::chrono::milliseconds(0);  // every success
  return options;
}

std::unique_ptr<Filmstrip> openStrip(FilmstripOptions options) {
  auto strip = Filmstrip::open(std::move(options));
  REQUIRE(strip);
  return std::move(*strip);
}

std::vector<uint64_t> ids(const std::vector<Entry>& entries) {
  std::vector<uint64_t> out;
  for (const auto& e : entries) out.push_back(e.id);
  return out;
}

}  // namespace

TEST_CASE("filmstrip entries keep the frame lossless and the request, reply and mapping",
          "[vision_app][filmstrip]") {
  test::TempDir dir;
  auto strip = openStrip(in(dir.file("strip")));
  const uint64_t id = strip->reserve();
  REQUIRE(strip->record(id, locateTake("OK 1 1.000 2.000 3.000", 77)));
  strip->flush();
  auto stored = strip->frame(id);
  REQUIRE(stored);
  CHECK(stored->first.request_line == "LOCATE 1");
  CHECK(stored->first.reply == "OK 1 1.000 2.000 3.000");
  CHECK_FALSE(stored->first.failure);
  CHECK(stored->first.camera == "cam0");
  CHECK(stored->first.sequence == 7);
  CHECK(stored->first.mapping.roi_x == 10);
  CHECK(stored->first.mapping.scale_x == 0.5);
  CHECK(stored->first.asked_type == 1);
  REQUIRE(stored->second.size() == cv::Size(64, 48));
  CHECK(cv::countNonZero(stored->second != 77) == 0);
  CHECK(fs::exists(dir.file("strip/0000000001.png")));
  CHECK(fs::exists(dir.file("strip/0000000001.json")));
}

TEST_CASE("a filmstrip entry records the frame its reply's poses are in",
          "[vision_app][filmstrip]") {
  test::TempDir dir;
  auto strip = openStrip(in(dir.file("strip")));
  // Robot millimetres once a transform is computed; vision pixels before
  // any calibration; no frame for a reply without poses.
  store::CellGeometry computed;
  computed.transform = calibration::PlaneTransform{};
  const uint64_t in_robot = strip->reserve();
  REQUIRE(strip->record(in_robot, locateTake("OK 1 1.000 2.000 3.000", 100, computed)));
  const uint64_t in_pixels = strip->reserve();
  REQUIRE(
      strip->record(in_pixels, locateTake("OK 1 1.000 2.000 3.000", 100, store::CellGeometry{})));
  const uint64_t none = strip->reserve();
  REQUIRE(strip->record(none, locateTake("ERROR 21 no frame", 100, computed)));
  const uint64_t nothing = strip->reserve();
  REQUIRE(strip->record(nothing, locateTake("OK 0", 100, computed)));
  strip->flush();
  CHECK(strip->entry(in_robot)->reply_frame == "robot_mm");
  CHECK(strip->entry(in_pixels)->reply_frame == "pixels");
  CHECK(strip->entry(none)->reply_frame.empty());
  CHECK(strip->entry(nothing)->reply_frame.empty());

  // A sidecar written before the frame was recorded has none; one naming
  // a frame that does not exist is damaged.
  auto text = readFile(dir.file("strip/0000000001.json"));
  REQUIRE(text);
  const std::string key = "\"reply_frame\":\"robot_mm\",";
  REQUIRE(text->find(key) != std::string::npos);
  std::string older = *text;
  older.erase(older.find(key), key.size());
  auto parsed = parseEntryJson(older);
  REQUIRE(parsed);
  CHECK(parsed->reply_frame.empty());
  std::string unknown = *text;
  unknown.replace(unknown.find("robot_mm"), 8, "robot_in");
  auto refused = parseEntryJson(unknown);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().message.find("reply_frame") != std::string::npos);
}

TEST_CASE("filmstrip bounds evict the oldest successes and keep the failures apart",
          "[vision_app][filmstrip]") {
  test::TempDir dir;
  FilmstripOptions options = in(dir.file("strip"));
  options.max_entries = 2;
  options.max_failures = 3;
  auto strip = openStrip(options);
  // Eight successes and three failures (nothing found, an error), mixed.
  std::vector<uint64_t> failures;
  for (int i = 0; i < 11; ++i) {
    const bool fail = i == 1 || i == 4 || i == 9;
    const uint64_t id = strip->reserve();
    REQUIRE(strip->record(
        id, locateTake(fail ? (i == 4 ? "ERROR 20 no frame" : "OK 0") : "OK 1 1.000 2.000 3.000")));
    if (fail) failures.push_back(id);
    strip->flush();  // one at a time: no drop by a full queue here
  }
  const auto kept = strip->list(100);
  // The newest two successes, and every failure, however old.
  CHECK(ids(kept) == std::vector<uint64_t>{11, 10, 9, 5, 2});
  CHECK(ids(strip->list(100, true)) == std::vector<uint64_t>{10, 5, 2});
  CHECK(strip->figures().evicted == 6);
  CHECK_FALSE(fs::exists(dir.file("strip/0000000001.json")));
  CHECK_FALSE(fs::exists(dir.file("strip/0000000001.png")));
  // A fourth failure pushes out the oldest failure, never a success.
  REQUIRE(strip->record(strip->reserve(), locateTake("OK 0")));
  strip->flush();
  CHECK(ids(strip->list(100)) == std::vector<uint64_t>{12, 11, 10, 9, 5});
}

TEST_CASE("filmstrip byte bounds hold", "[vision_app][filmstrip]") {
  test::TempDir dir;
  FilmstripOptions options = in(dir.file("strip"));
  options.max_bytes = 1;  // less than one entry: none kept
  auto strip = openStrip(options);
  REQUIRE(strip->record(strip->reserve(), locateTake("OK 1 1.000 2.000 3.000")));
  REQUIRE(strip->record(strip->reserve(), locateTake("OK 0")));
  strip->flush();
  CHECK(ids(strip->list(100)) == std::vector<uint64_t>{2});
}

TEST_CASE("a full filmstrip queue drops successes first and counts every drop",
          "[vision_app][filmstrip]") {
  test::TempDir dir;
  FilmstripOptions options = in(dir.file("strip"));
  options.queue = 2;
  // The writer held on the first entry until the queue is filled.
  std::promise<void> writing;
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  std::once_flag first;
  options.before_write = [&](uint64_t) {
    std::call_once(first, [&] {
      writing.set_value();
      released.wait();
    });
  };
  auto strip = openStrip(options);
  const std::string ok = "OK 1 1.000 2.000 3.000";
  REQUIRE(strip->record(1, locateTake(ok)));  // taken by the writer
  writing.get_future().wait();
  CHECK(strip->record(2, locateTake(ok)));        // queue: 2
  CHECK(strip->record(3, locateTake("OK 0")));    // queue: 2 3 (full)
  CHECK_FALSE(strip->record(4, locateTake(ok)));  // a success: dropped
  CHECK(strip->record(5, locateTake("OK 0")));    // takes success 2's place: 3 5
  CHECK(strip->record(6, locateTake("OK 0")));    // only failures: the oldest goes, 5 6
  release.set_value();
  strip->flush();
  CHECK(ids(strip->list(100)) == std::vector<uint64_t>{6, 5, 1});
  const auto f = strip->figures();
  CHECK(f.dropped_successes == 2);
  CHECK(f.dropped_failures == 1);
  CHECK(f.recorded == 3);
}

TEST_CASE("a damaged filmstrip sidecar is reported by name and skipped, never a crash",
          "[vision_app][filmstrip]") {
  test::TempDir dir;
  {
    auto strip = openStrip(in(dir.file("strip")));
    for (int i = 0; i < 3; ++i) REQUIRE(strip->record(strip->reserve(), locateTake("OK 0")));
    strip->flush();
    // Damaged while the app runs: the read says so, by name.
    std::ofstream(dir.file("strip/0000000002.json")) << "{\"id\": 2, \"time_ms\": ";
    auto e = strip->entry(2);
    REQUIRE_FALSE(e);
    CHECK(e.error().code == FilmstripErrc::kDamaged);
    CHECK(e.error().message.find("0000000002.json") != std::string::npos);
    CHECK_FALSE(strip->frame(2));
    CHECK(strip->entry(3));
  }
  // Mistyped fields, an id that is not the name's, an image path.
  auto text = readFile(dir.file("strip/0000000003.json"));
  REQUIRE(text);
  std::ofstream(dir.file("strip/0000000004.json"))
      << std::string(*text).replace(text->find("\"id\":3"), 6, "\"id\":9");
  std::string path_image = *text;
  path_image.replace(path_image.find("0000000003.png"), 14, "../../etc/pass");
  std::ofstream(dir.file("strip/0000000001.json")) << path_image;
  std::ofstream(dir.file("strip/0000000005.png")) << "not a png";
  auto strip = openStrip(in(dir.file("strip")));
  CHECK(ids(strip->list(100)) == std::vector<uint64_t>{3});
  const auto& problems = strip->problems();
  REQUIRE(problems.size() == 4);
  CHECK(problems[0].find("0000000001.json") != std::string::npos);
  CHECK(problems[1].find("0000000002.json") != std::string::npos);
  CHECK(problems[2].find("0000000004.json") != std::string::npos);
  CHECK(problems[3].find("0000000005.png") != std::string::npos);
  // Nothing damaged was removed, and new ids do not reuse theirs.
  CHECK(fs::exists(dir.file("strip/0000000002.json")));
  CHECK(strip->reserve() == 6);
  CHECK(strip->entry(2).error().code == FilmstripErrc::kNoEntry);
}

TEST_CASE("a WHY entry shares its LOCATE's frame, which outlives the LOCATE's entry",
          "[vision_app][filmstrip]") {
  test::TempDir dir;
  FilmstripOptions options = in(dir.file("strip"));
  options.max_entries = 1;
  auto strip = openStrip(options);
  REQUIRE(strip->record(1, locateTake("OK 1 1.000 2.000 3.000", 55)));
  auto why = std::make_shared<results::RequestRecord>();
  why->request = "WHY";
  why->request_line = "WHY";
  why->reply = "OK 1 region 0 no model";
  REQUIRE(strip->record(2, {why, nullptr, "WHY", 1}));
  REQUIRE(strip->record(3, locateTake("OK 1 1.000 2.000 3.000")));  // evicts 1
  strip->flush();
  CHECK(ids(strip->list(100)) == std::vector<uint64_t>{3, 2});
  auto stored = strip->frame(2);
  REQUIRE(stored);
  CHECK(stored->first.failure);
  CHECK(stored->first.explains == 1);
  CHECK(stored->first.why == "OK 1 region 0 no model");
  CHECK(stored->first.asked_type == 1);
  CHECK(cv::countNonZero(stored->second != 55) == 0);
}

TEST_CASE("a filmstrip export is a folder a dir: camera serves in order",
          "[vision_app][filmstrip]") {
  test::TempDir dir;
  auto strip = openStrip(in(dir.file("strip")));
  for (int level : {10, 20, 30})
    REQUIRE(strip->record(strip->reserve(), locateTake("OK 0", level)));
  strip->flush();
  auto written = strip->exportTo(dir.file("export"), {1, 3, 99});
  REQUIRE(written);
  CHECK(*written == 2);
  // Only images where a dir: camera looks; sidecars in a hidden folder.
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir.file("export")))
    names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  CHECK(names == std::vector<std::string>{".filmstrip", "000001.png", "000002.png"});
  CHECK(picksight::codecs::imread(dir.file("export/000002.png"), cv::IMREAD_UNCHANGED)
            .at<uchar>(0, 0) == 30);
  CHECK(fs::exists(dir.file("export/.filmstrip/000002.json")));
  auto again = strip->exportTo(dir.file("export"), {1});
  REQUIRE_FALSE(again);
  CHECK(again.error().code == FilmstripErrc::kStorage);
}

TEST_CASE("successes closer than the interval are sampled out, failures never",
          "[vision_app][filmstrip]") {
  test::TempDir dir;
  FilmstripOptions options = in(dir.file("strip"));
  options.success_interval = std::chrono::hours(1);
  auto strip = openStrip(options);
  const std::string ok = "OK 1 1.000 2.000 3.000";
  CHECK(strip->record(1, locateTake(ok)));
  CHECK_FALSE(strip->record(2, locateTake(ok)));
  CHECK(strip->record(3, locateTake("OK 0")));
  CHECK(strip->record(4, locateTake("ERROR 20 no frame")));
  CHECK_FALSE(strip->record(5, locateTake(ok)));
  strip->flush();
  CHECK(ids(strip->list(100)) == std::vector<uint64_t>{4, 3, 1});
  CHECK(strip->figures().sampled_out == 2);
}

TEST_CASE("filmstrip errors are robot codes 55 to 59", "[vision_app][filmstrip]") {
  CHECK(protocol::robotErrorCode(FilmstripErrc::kNoEntry) == 55);
  CHECK(protocol::robotErrorCode(FilmstripErrc::kDamaged) == 56);
  CHECK(protocol::robotErrorCode(FilmstripErrc::kOff) == 57);
  CHECK(protocol::robotErrorCode(FilmstripErrc::kStorage) == 58);
  CHECK(protocol::robotErrorCode(FilmstripErrc::kNoFrame) == 59);
}

TEST_CASE("a failure is an ERROR or a reply of no pose", "[vision_app][filmstrip]") {
  CHECK(isFailureReply("OK 0"));
  CHECK(isFailureReply("OK 0 "));
  CHECK(isFailureReply("ERROR 20 no frame"));
  CHECK(isFailureReply(""));
  CHECK_FALSE(isFailureReply("OK 1 1.000 2.000 3.000"));
  CHECK_FALSE(isFailureReply("OK 10 1 1.000 2.000 3.000"));
}
