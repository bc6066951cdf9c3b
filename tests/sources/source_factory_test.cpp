// Pins the source factory: scheme dispatch and errors that name what is wrong
// with a source string, including the synthetic source's key=value options.
#include <string>

#include <catch2/catch.hpp>

#include <opencv2/imgproc.hpp>

#include "picksight/sources/source.hpp"

using namespace std::chrono_literals;
using picksight::video::makeSource;

namespace {

// The error message of a source string that must fail with SourceErrc::kBadConfig.
std::string badConfigMessage(const std::string& uri) {
  auto source = makeSource(uri);
  if (source) return "accepted";
  CHECK(source.error().code == picksight::video::SourceErrc::kBadConfig);
  return source.error().message;
}

}  // namespace

TEST_CASE("makeSource rejects a string without a known scheme", "[video_server]") {
  CHECK_THAT(badConfigMessage("camera0"), Catch::Contains("scheme"));
  CHECK_THAT(badConfigMessage(""), Catch::Contains("scheme"));
  const std::string unknown = badConfigMessage("gige:cam-0042");
  CHECK_THAT(unknown, Catch::Contains("'gige'"));
  CHECK_THAT(unknown, Catch::Contains("synthetic:"));
}

TEST_CASE("makeSource file: needs a path", "[video_server]") {
  CHECK_THAT(badConfigMessage("file:"), Catch::Contains("path"));
  // A path is enough to build it; whether the file exists is known at open().
  CHECK(makeSource("file:/nonexistent/picksight.png"));
}

TEST_CASE("makeSource synthetic: errors name the key and what it must be", "[video_server]") {
  CHECK_THAT(badConfigMessage("synthetic:parts=abc"),
             Catch::StartsWith("synthetic: parts must be") && Catch::Contains("'abc'"));
  CHECK_THAT(badConfigMessage("synthetic:parts=-1"), Catch::StartsWith("synthetic: parts must be"));
  CHECK_THAT(badConfigMessage("synthetic:width=10"), Catch::StartsWith("synthetic: width must be"));
  CHECK_THAT(badConfigMessage("synthetic:width=320,height=1.5"),
             Catch::StartsWith("synthetic: height must be"));
  CHECK_THAT(badConfigMessage("synthetic:noise=loud"),
             Catch::StartsWith("synthetic: noise must be"));
  CHECK_THAT(badConfigMessage("synthetic:light=dim"),
             Catch::StartsWith("synthetic: light must be"));
  CHECK_THAT(badConfigMessage("synthetic:types=rectangle+blob"),
             Catch::StartsWith("synthetic: types must be") && Catch::Contains("rectangle"));
  CHECK_THAT(badConfigMessage("synthetic:colour=red"), Catch::Contains("unknown key 'colour'"));
  CHECK_THAT(badConfigMessage("synthetic:parts"), Catch::Contains("key=value"));
}

TEST_CASE("makeSource synthetic: builds a source with the asked sensor size", "[video_server]") {
  auto source = makeSource("synthetic:width=320,height=240,parts=2,seed=5,noise=0");
  REQUIRE(source);
  auto& s = **source;
  REQUIRE(s.open());
  const auto info = s.info();
  CHECK(info.model == "synthetic");
  CHECK(info.sensor_width == 320);
  CHECK(info.sensor_height == 240);
  CHECK_FALSE(info.formats.empty());
  auto frame = s.grab(1000ms);
  REQUIRE(frame);
  CHECK(frame->image.size() == cv::Size(320, 240));
  CHECK(frame->image.type() == CV_8UC1);
  CHECK(frame->truth.size() == 2);
  for (const auto& part : frame->truth) {
    CHECK(part.x >= 0);
    CHECK(part.x < 320);
    CHECK(part.y >= 0);
    CHECK(part.y < 240);
  }
  s.close();
}

TEST_CASE("makeSource synthetic: with no options uses the defaults", "[video_server]") {
  auto source = makeSource("synthetic:");
  REQUIRE(source);
  REQUIRE((*source)->open());
  CHECK((*source)->info().sensor_width > 0);
  CHECK((*source)->info().sensor_height > 0);
}

TEST_CASE("makeSource synthetic: a front light's scene with its belt and shadows",
          "[video_server]") {
  // The front lights the vision app is measured under, for trying a cell's
  // settings without its camera; grey only, as this camera is.
  CHECK_THAT(badConfigMessage("synthetic:light=colour"),
             Catch::StartsWith("synthetic: light must be") && Catch::Contains("low-contrast"));
  const auto frameUnder = [](const std::string& light) {
    auto source =
        makeSource("synthetic:width=640,height=480,parts=3,seed=7,noise=0,light=" + light);
    REQUIRE(source);
    REQUIRE((*source)->open());
    auto frame = (*source)->grab(1000ms);
    REQUIRE(frame);
    REQUIRE(frame->image.type() == CV_8UC1);
    return *frame;
  };
  const auto uneven = frameUnder("uneven");
  const auto textured = frameUnder("textured");
  const auto shadow = frameUnder("shadow");
  // The same parts under every light: the truth is the part.
  REQUIRE(textured.truth.size() == uneven.truth.size());
  REQUIRE(shadow.truth.size() == uneven.truth.size());
  for (size_t i = 0; i < uneven.truth.size(); ++i) {
    CHECK(textured.truth[i].x == uneven.truth[i].x);
    CHECK(shadow.truth[i].y == uneven.truth[i].y);
  }
  // The belt's grain and blotches: detail a smooth light has not.
  cv::Mat smooth;
  cv::Mat grainy;
  cv::Laplacian(uneven.image, smooth, CV_32F);
  cv::Laplacian(textured.image, grainy, CV_32F);
  CHECK(cv::mean(cv::abs(grainy))[0] > 4 * cv::mean(cv::abs(smooth))[0]);
  // A cast shadow only darkens the surface beside each part.
  cv::Mat darker;
  cv::Mat lighter;
  cv::subtract(textured.image, shadow.image, darker);
  cv::subtract(shadow.image, textured.image, lighter);
  CHECK(cv::countNonZero(darker > 20) > 300);
  CHECK(cv::countNonZero(lighter > 1) == 0);
}
