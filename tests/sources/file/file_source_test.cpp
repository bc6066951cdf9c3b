// Pins the file camera: serves the image on every grab, picks up a new image
// renamed over the path (even with equal size and mtime), keeps the last good
// image while the file is missing or half-written, and fails cleanly.
#include <fcntl.h>
#include <sys/stat.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>

#include <catch2/catch.hpp>

#include <opencv2/core.hpp>
#include "picksight/codecs/codecs.hpp"
#include "temp_dir.hpp"

#include "picksight/sources/source.hpp"

using namespace std::chrono_literals;
namespace fs = std::filesystem;
using picksight::video::makeSource;
using picksight::video::Source;

namespace {

using picksight::test::TempDir;

// A mono image whose content depends on `seed`.
cv::Mat sceneImage(int seed) {
  cv::Mat image(48, 64, CV_8UC1);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      image.at<uint8_t>(y, x) = static_cast<uint8_t>((x * 3 + y * 5 + seed * 101) % 256);
    }
  }
  return image;
}

bool sameImage(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

std::unique_ptr<Source> fileSource(const std::string& path) {
  auto source = makeSource("file:" + path);
  REQUIRE(source);
  return std::move(*source);
}

cv::Mat grabImage(Source& source) {
  auto frame = source.grab(1000ms);
  REQUIRE(frame);
  return frame->image;
}

struct stat statOf(const std::string& path) {
  struct stat st {};
  REQUIRE(::stat(path.c_str(), &st) == 0);
  return st;
}

}  // namespace

TEST_CASE("FileSource serves the image on every grab", "[video_server]") {
  TempDir dir;
  const std::string path = dir.file("scene.png");
  const cv::Mat a = sceneImage(1);
  REQUIRE(picksight::codecs::imwrite(path, a));
  auto source = fileSource(path);
  REQUIRE(source->open());
  const auto info = source->info();
  CHECK(info.sensor_width == 64);
  CHECK(info.sensor_height == 48);
  CHECK(info.serial == path);
  CHECK(sameImage(grabImage(*source), a));
  CHECK(sameImage(grabImage(*source), a));
}

TEST_CASE("FileSource serves colour as BGR and 16-bit images as 8-bit", "[video_server]") {
  TempDir dir;
  SECTION("colour") {
    cv::Mat bgr(10, 12, CV_8UC3, cv::Scalar(10, 20, 30));
    const std::string path = dir.file("colour.png");
    REQUIRE(picksight::codecs::imwrite(path, bgr));
    auto source = fileSource(path);
    REQUIRE(source->open());
    const cv::Mat image = grabImage(*source);
    REQUIRE(image.type() == CV_8UC3);
    CHECK(image.at<cv::Vec3b>(5, 5) == cv::Vec3b(10, 20, 30));
  }
  SECTION("16-bit") {
    cv::Mat deep(10, 12, CV_16UC1, cv::Scalar(200 * 257));
    const std::string path = dir.file("deep.png");
    REQUIRE(picksight::codecs::imwrite(path, deep));
    auto source = fileSource(path);
    REQUIRE(source->open());
    const cv::Mat image = grabImage(*source);
    REQUIRE(image.type() == CV_8UC1);
    CHECK(int(image.at<uint8_t>(3, 3)) == 200);
  }
}

TEST_CASE("FileSource marks a JPEG's frames compressed, by its content, not its name",
          "[video_server]") {
  TempDir dir;
  const cv::Mat bgr(48, 64, CV_8UC3, cv::Scalar(40, 160, 70));
  std::vector<uint8_t> jpeg;
  REQUIRE(picksight::codecs::imencode(".jpg", bgr, jpeg));
  const std::string named_png = dir.file("photo.png");
  std::ofstream(named_png, std::ios::binary)
      .write(reinterpret_cast<const char*>(jpeg.data()), static_cast<std::streamsize>(jpeg.size()));
  auto source = fileSource(named_png);
  REQUIRE(source->open());
  auto frame = source->grab(1000ms);
  REQUIRE(frame);
  CHECK(frame->compressed);
  // A lossless image, even named .jpg, is not.
  const std::string lossless = dir.file("photo.jpg.png");
  REQUIRE(picksight::codecs::imwrite(lossless, bgr));
  const std::string named_jpg = dir.file("lossless.jpg");
  REQUIRE(std::rename(lossless.c_str(), named_jpg.c_str()) == 0);
  auto plain = fileSource(named_jpg);
  REQUIRE(plain->open());
  auto kept = plain->grab(1000ms);
  REQUIRE(kept);
  CHECK_FALSE(kept->compressed);
}

TEST_CASE("FileSource picks up a new image renamed over the path", "[video_server]") {
  TempDir dir;
  const std::string path = dir.file("scene.png");
  REQUIRE(picksight::codecs::imwrite(path, sceneImage(1)));
  auto source = fileSource(path);
  REQUIRE(source->open());
  CHECK(sameImage(grabImage(*source), sceneImage(1)));

  const std::string tmp = dir.file("scene.tmp.png");
  REQUIRE(picksight::codecs::imwrite(tmp, sceneImage(2)));
  REQUIRE(std::rename(tmp.c_str(), path.c_str()) == 0);
  CHECK(sameImage(grabImage(*source), sceneImage(2)));
  CHECK(sameImage(grabImage(*source), sceneImage(2)));
}

TEST_CASE("FileSource picks up a renamed image of equal size and mtime (new inode)",
          "[video_server]") {
  TempDir dir;
  // PGM: the file size depends only on the image size.
  const std::string path = dir.file("scene.pgm");
  REQUIRE(picksight::codecs::imwrite(path, sceneImage(1)));
  auto source = fileSource(path);
  REQUIRE(source->open());
  CHECK(sameImage(grabImage(*source), sceneImage(1)));
  const struct stat before = statOf(path);

  const std::string tmp = dir.file("scene.tmp.pgm");
  REQUIRE(picksight::codecs::imwrite(tmp, sceneImage(2)));
  const timespec times[2] = {before.st_atim, before.st_mtim};
  REQUIRE(::utimensat(AT_FDCWD, tmp.c_str(), times, 0) == 0);
  REQUIRE(std::rename(tmp.c_str(), path.c_str()) == 0);

  const struct stat after = statOf(path);
  REQUIRE(after.st_size == before.st_size);
  REQUIRE(after.st_mtim.tv_sec == before.st_mtim.tv_sec);
  REQUIRE(after.st_mtim.tv_nsec == before.st_mtim.tv_nsec);
  REQUIRE(after.st_ino != before.st_ino);
  CHECK(sameImage(grabImage(*source), sceneImage(2)));
}

TEST_CASE("FileSource of a missing file is SourceErrc::kUnavailable naming the path",
          "[video_server]") {
  TempDir dir;
  const std::string path = dir.file("absent.png");
  auto source = fileSource(path);
  auto opened = source->open();
  REQUIRE_FALSE(opened);
  CHECK(opened.error().code == picksight::video::SourceErrc::kUnavailable);
  CHECK_THAT(opened.error().message, Catch::Contains(path));
  auto grabbed = source->grab(100ms);
  REQUIRE_FALSE(grabbed);
  CHECK(grabbed.error().code == picksight::video::SourceErrc::kUnavailable);
}

TEST_CASE("FileSource of a file that is not an image is SourceErrc::kUnavailable",
          "[video_server]") {
  TempDir dir;
  const std::string path = dir.file("garbage.png");
  std::ofstream(path) << "this is not a PNG";
  auto source = fileSource(path);
  auto opened = source->open();
  REQUIRE_FALSE(opened);
  CHECK(opened.error().code == picksight::video::SourceErrc::kUnavailable);
}

TEST_CASE("FileSource keeps the last image while the file is missing or unreadable",
          "[video_server]") {
  TempDir dir;
  const std::string path = dir.file("scene.png");
  REQUIRE(picksight::codecs::imwrite(path, sceneImage(1)));
  auto source = fileSource(path);
  REQUIRE(source->open());
  CHECK(sameImage(grabImage(*source), sceneImage(1)));

  REQUIRE(std::remove(path.c_str()) == 0);
  CHECK(sameImage(grabImage(*source), sceneImage(1)));

  std::ofstream(path) << "half-written";
  CHECK(sameImage(grabImage(*source), sceneImage(1)));

  const std::string tmp = dir.file("scene.tmp.png");
  REQUIRE(picksight::codecs::imwrite(tmp, sceneImage(3)));
  REQUIRE(std::rename(tmp.c_str(), path.c_str()) == 0);
  CHECK(sameImage(grabImage(*source), sceneImage(3)));
}

TEST_CASE("FileSource fails once the file stays gone or unreadable past the grace period",
          "[video_server]") {
  TempDir dir;
  const std::string path = dir.file("scene.png");
  REQUIRE(picksight::codecs::imwrite(path, sceneImage(1)));
  auto source = fileSource(path);
  REQUIRE(source->open());
  CHECK(sameImage(grabImage(*source), sceneImage(1)));

  std::ofstream(path) << "";  // truncated to nothing
  // The last image stands in for a moment, then never again.
  picksight::Result<picksight::video::SourceFrame> grabbed = source->grab(100ms);
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (grabbed && std::chrono::steady_clock::now() < deadline) {
    CHECK(sameImage(grabbed->image, sceneImage(1)));
    std::this_thread::sleep_for(20ms);
    grabbed = source->grab(100ms);
  }
  REQUIRE_FALSE(grabbed);
  CHECK(grabbed.error().code == picksight::video::SourceErrc::kUnavailable);
  CHECK_THAT(grabbed.error().message, Catch::Contains(path) &&
                                          Catch::Contains("not a readable image") &&
                                          Catch::Contains("for more than 1000 ms"));
  CHECK_FALSE(source->grab(100ms));

  // As the camera does: close, then open again until the file is back.
  source->close();
  CHECK_FALSE(source->open());
  REQUIRE(picksight::codecs::imwrite(path, sceneImage(2)));
  REQUIRE(source->open());
  CHECK(sameImage(grabImage(*source), sceneImage(2)));
}
