// Pins the directory driver: images in name order, looping, the listing
// re-read when files come and go, unreadable and hidden files skipped,
// 16-bit images kept as Mono16; and, end to end, a real
// picksight-video-server publishing a directory's images in order.
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <catch2/catch.hpp>

#include <zmq.hpp>
#include "picksight/codecs/codecs.hpp"
#include "temp_dir.hpp"

#include "picksight/sources/source.hpp"
#include "picksight/tool_support/subprocess.hpp"
#include "picksight/transport/frame_message.hpp"
#include "picksight/video_server/pixel_format.hpp"

using namespace std::chrono_literals;
using namespace picksight::video;
namespace fs = std::filesystem;

namespace {

using picksight::test::TempDir;

// A flat grey image whose level identifies it.
void writeImage(const fs::path& file, int level, cv::Size size = {32, 24}) {
  REQUIRE(picksight::codecs::imwrite(file.string(), cv::Mat(size, CV_8UC1, cv::Scalar(level))));
}

int levelOf(Source& source) {
  auto frame = source.grab(1s);
  if (!frame) FAIL(frame.error().message);
  auto grey = toOutputFormat(frame->image, frame->layout, OutputFormat::kMono8);
  REQUIRE(grey);
  return static_cast<int>(cv::mean(*grey)[0] + 0.5);
}

std::unique_ptr<Source> dirSource(const fs::path& dir) {
  auto made = makeSource("dir:" + dir.string());
  REQUIRE(made);
  return std::move(*made);
}

}  // namespace

TEST_CASE("dir: images in name order, looping, unreadable and hidden files skipped",
          "[video_server][dir]") {
  TempDir dir;
  // Written out of order: the order served is the names'.
  writeImage(dir.path() / "frame_002.png", 30);
  writeImage(dir.path() / "frame_000.png", 10);
  writeImage(dir.path() / "frame_001.png", 20);
  std::ofstream(dir.path() / "frame_001b.png") << "not an image";
  writeImage(dir.path() / ".frame_0015.png", 99);  // a writer's temporary
  fs::create_directory(dir.path() / "frame_0016.png");
  auto source = dirSource(dir.path());
  CHECK_FALSE(source->streams());
  REQUIRE(source->open());
  CHECK(source->info().sensor_width == 32);
  CHECK(source->info().sensor_height == 24);
  for (int expected : {10, 20, 30, 10, 20, 30, 10}) CHECK(levelOf(*source) == expected);
}

TEST_CASE("dir: the listing is re-read when files come and go", "[video_server][dir]") {
  TempDir dir;
  writeImage(dir.path() / "a.png", 10);
  writeImage(dir.path() / "c.png", 30);
  auto source = dirSource(dir.path());
  REQUIRE(source->open());
  CHECK(levelOf(*source) == 10);
  writeImage(dir.path() / "b.png", 20);
  CHECK(levelOf(*source) == 20);  // goes on after "a", so the new "b" is next
  CHECK(levelOf(*source) == 30);
  fs::remove(dir.path() / "a.png");
  CHECK(levelOf(*source) == 20);  // wrapped past the removed "a"
  // A file rewritten in place is read afresh.
  writeImage(dir.path() / "c.png", 77);
  CHECK(levelOf(*source) == 77);
}

TEST_CASE("dir: 16-bit images are Mono16, colour images BGR8", "[video_server][dir]") {
  TempDir dir;
  REQUIRE(picksight::codecs::imwrite((dir.path() / "0.png").string(),
                                     cv::Mat(8, 8, CV_16UC1, cv::Scalar(257 * 200))));
  REQUIRE(picksight::codecs::imwrite((dir.path() / "1.png").string(),
                                     cv::Mat(8, 8, CV_8UC3, cv::Scalar(10, 20, 30))));
  auto source = dirSource(dir.path());
  REQUIRE(source->open());
  auto deep = source->grab(1s);
  REQUIRE(deep);
  CHECK(deep->layout == PixelLayout::kMono16);
  CHECK_FALSE(deep->compressed);
  CHECK(levelOf(*source) == 22);  // the colour one, grey: 0.114*10 + 0.587*20 + 0.299*30
  auto again = source->grab(1s);
  REQUIRE(again);
  auto grey = toOutputFormat(again->image, again->layout, OutputFormat::kMono8);
  REQUIRE(grey);
  CHECK(grey->at<uint8_t>(0, 0) == 200);
}

TEST_CASE("dir: a JPEG's frame is marked compressed, a PNG's is not", "[video_server][dir]") {
  TempDir dir;
  const cv::Mat bgr(8, 8, CV_8UC3, cv::Scalar(10, 20, 30));
  REQUIRE(picksight::codecs::imwrite((dir.path() / "0.jpg").string(), bgr));
  REQUIRE(picksight::codecs::imwrite((dir.path() / "1.png").string(), bgr));
  auto source = dirSource(dir.path());
  REQUIRE(source->open());
  auto jpeg = source->grab(1s);
  REQUIRE(jpeg);
  CHECK(jpeg->compressed);
  auto png = source->grab(1s);
  REQUIRE(png);
  CHECK_FALSE(png->compressed);
}

TEST_CASE("dir: empty, missing or unreadable directories are unavailable", "[video_server][dir]") {
  TempDir dir;
  auto source = dirSource(dir.path());
  auto empty = source->open();
  REQUIRE_FALSE(empty);
  CHECK(empty.error().code == SourceErrc::kUnavailable);
  std::ofstream(dir.path() / "broken.png") << "no";
  auto unreadable = source->open();
  REQUIRE_FALSE(unreadable);
  CHECK_THAT(unreadable.error().message, Catch::Contains("no readable image"));
  // The camera retries with back-off: an image that appears is served.
  writeImage(dir.path() / "good.png", 50);
  REQUIRE(source->open());
  CHECK(levelOf(*source) == 50);

  auto missing = dirSource(dir.path() / "nope");
  auto opened = missing->open();
  REQUIRE_FALSE(opened);
  CHECK(opened.error().code == SourceErrc::kUnavailable);
  CHECK_THAT(opened.error().message, Catch::Contains("nope"));
  CHECK(makeSource("dir:").error().code == SourceErrc::kBadConfig);
}

TEST_CASE("picksight-video-server publishes a dir: source's images in order",
          "[video_server][dir][e2e]") {
  TempDir dir;
  constexpr int kImages = 4;
  for (int i = 0; i < kImages; ++i) {
    writeImage(dir.path() / ("img_" + std::to_string(i) + ".png"), 40 + 50 * i, {64, 48});
  }
  picksight::tool_support::Subprocess server(
      {std::string(PICKSIGHT_BIN_DIR) + "/picksight-video-server", "--source",
       "cam0=dir:" + dir.path().string(), "--fps", "20", "--frames", "tcp://127.0.0.1:*",
       "--control", "tcp://127.0.0.1:*"});
  auto endpoint = server.waitForLine("frames ", 10s);
  REQUIRE(endpoint);
  zmq::context_t context;
  picksight::transport::FrameSubscriber subscriber(context, *endpoint, "cam0", 64);
  // Sequence numbers count frames from 1 with none given to failures, so
  // frame s is image (s - 1) mod n; checking that per frame holds even when
  // the subscriber misses some.
  int received = 0;
  int distinct_mask = 0;
  for (int tries = 0; tries < 200 && received < 3 * kImages; ++tries) {
    auto frame = subscriber.receive(5s);
    REQUIRE(frame);
    const cv::Mat image = frame->image;
    REQUIRE(image.size() == cv::Size(64, 48));
    const int image_index = static_cast<int>((frame->info.sequence - 1) % kImages);
    INFO("sequence " << frame->info.sequence);
    CHECK(std::abs(cv::mean(image)[0] - (40 + 50 * image_index)) < 1);
    distinct_mask |= 1 << image_index;
    ++received;
  }
  CHECK(received == 3 * kImages);
  CHECK(distinct_mask == (1 << kImages) - 1);
}
