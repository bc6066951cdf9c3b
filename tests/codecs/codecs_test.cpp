// The codecs facade: what OpenCV's imgcodecs and videoio would answer, from a
// module no program links (picksight/codecs/codecs.hpp).
#include "picksight/codecs/codecs.hpp"

#include <catch2/catch.hpp>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "cell_fixture.hpp"
#include "temp_dir.hpp"

namespace fs = std::filesystem;
using picksight::test::TempDir;

namespace {

cv::Mat gradient(int type) {
  cv::Mat m(37, 53, type);
  cv::randu(m, cv::Scalar::all(0), cv::Scalar::all(255));
  return m;
}

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

// The NEEDED entries of an ELF file's dynamic section, as readelf prints them.
std::string neededLibraries(const std::string& file) {
  std::string out;
  std::unique_ptr<FILE, int (*)(FILE*)> p(popen(("readelf -d '" + file + "'").c_str(), "r"),
                                          pclose);
  REQUIRE(p);
  char buf[512];
  while (fgets(buf, sizeof buf, p.get()))
    if (std::string(buf).find("(NEEDED)") != std::string::npos) out += buf;
  return out;
}

}  // namespace

TEST_CASE("images go through the module as through OpenCV", "[codecs]") {
  TempDir dir;
  for (int type : {CV_8UC1, CV_8UC3, CV_16UC1}) {
    const cv::Mat image = gradient(type);
    std::vector<uchar> png;
    REQUIRE(picksight::codecs::imencode(".png", image, png, {cv::IMWRITE_PNG_COMPRESSION, 1}));
    CHECK(same(picksight::codecs::imdecode(png, cv::IMREAD_UNCHANGED), image));
    const std::string file = dir.file("image" + std::to_string(type) + ".png");
    REQUIRE(picksight::codecs::imwrite(file, image));
    CHECK(same(picksight::codecs::imread(file, cv::IMREAD_UNCHANGED), image));
  }
  // Colour read as grey, and JPEG's loss within a few levels.
  const cv::Mat colour = gradient(CV_8UC3);
  cv::GaussianBlur(colour, colour, {0, 0}, 3);
  const std::string jpeg = dir.file("image.jpg");
  REQUIRE(picksight::codecs::imwrite(jpeg, colour, {cv::IMWRITE_JPEG_QUALITY, 95}));
  const cv::Mat grey = picksight::codecs::imread(jpeg, cv::IMREAD_GRAYSCALE);
  CHECK(grey.type() == CV_8UC1);
  CHECK(grey.size() == colour.size());
  // What OpenCV answers for what it cannot do: an empty image, false.
  CHECK(picksight::codecs::imread(dir.file("missing.png")).empty());
  CHECK(picksight::codecs::imdecode(std::vector<uchar>{1, 2, 3}, cv::IMREAD_COLOR).empty());
  CHECK(picksight::codecs::haveImageWriter("a.png"));
  CHECK_FALSE(picksight::codecs::haveImageWriter("a.unknown-format"));
}

TEST_CASE("a video stream from the module reports a file it cannot open", "[codecs]") {
  auto capture = picksight::codecs::newVideoStream();
  REQUIRE(capture);
  CHECK_FALSE(capture->isOpened());
  TempDir dir;
  CHECK_FALSE(capture->open(dir.file("missing.mp4"), cv::CAP_FFMPEG, {}));
  CHECK_FALSE(capture->isOpened());
}

TEST_CASE("the module lies where the facade looks for it", "[codecs]") {
  const fs::path module = picksight::codecs::modulePath();
  CHECK(module.filename() == "libpicksight_codecs.so");
  CHECK(fs::is_regular_file(module));
  CHECK(module.parent_path().filename() == "picksight");
}

TEST_CASE("no program starts with imgcodecs or videoio linked", "[codecs]") {
  // Each costs a program's every start about a tenth of a second of CPU; the
  // module loads them when an image or a stream is first asked for.
  int programs = 0;
  for (const auto& entry : fs::directory_iterator(PICKSIGHT_BIN_DIR)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("picksight-", 0) != 0 || !entry.is_regular_file()) continue;
    ++programs;
    INFO(name);
    const std::string needed = neededLibraries(entry.path().string());
    CHECK(needed.find("libopencv_imgcodecs") == std::string::npos);
    CHECK(needed.find("libopencv_videoio") == std::string::npos);
  }
  CHECK(programs >= 6);
  // The module itself does link them.
  CHECK(neededLibraries(picksight::codecs::modulePath()).find("libopencv_imgcodecs") !=
        std::string::npos);
}

TEST_CASE("a program whose codecs module is missing says which file it looked for", "[codecs]") {
  TempDir dir;
  fs::create_directories(dir.path() / "bin");
  const fs::path program = dir.path() / "bin" / "picksight-vision";
  fs::copy_file(fs::path(PICKSIGHT_BIN_DIR) / "picksight-vision", program);
  cv::Mat image(40, 40, CV_8UC1, cv::Scalar(200));
  const std::string file = dir.file("frame.png");
  REQUIRE(picksight::codecs::imwrite(file, image));
  const auto r = picksight::e2e::run({"/bin/sh", "-c",
                                      "'" + program.string() + "' locate --data-dir '" +
                                          dir.file("data") + "' '" + file + "' 2>&1"});
  INFO(r.out);
  CHECK(r.exit_code == 1);
  CHECK(r.out.find("cannot open the image and video codecs (" +
                   (dir.path() / "lib" / "picksight" / "libpicksight_codecs.so").string()) !=
        std::string::npos);
}
