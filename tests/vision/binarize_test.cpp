// Binarization under uneven light: the adaptive method keeps parts whole and
// finds them where a global threshold cannot.
#include <catch2/catch.hpp>

#include <vector>

#include <opencv2/imgproc.hpp>

#include "picksight/vision/segmentation/binarize.hpp"
#include "picksight/vision/segmentation/regions.hpp"

using namespace picksight::vision;

namespace {
// A background lit from `left` to `right` grey levels across the image, with
// dark square parts reflecting `reflectance` of the local light, and noise.
cv::Mat litScene(int width, int height, double left, double right,
                 const std::vector<cv::Rect>& parts, double reflectance, double noise = 2.0) {
  cv::Mat light(height, width, CV_32F);
  for (int x = 0; x < width; ++x) light.col(x).setTo(left + (right - left) * x / (width - 1));
  cv::Mat reflect(height, width, CV_32F, cv::Scalar(1.0));
  for (const auto& r : parts) reflect(r).setTo(reflectance);
  cv::Mat img = light.mul(reflect);
  cv::Mat n(height, width, CV_32F);
  cv::RNG rng(7);
  rng.fill(n, cv::RNG::NORMAL, 0, noise);
  img += n;
  cv::Mat out;
  img.convertTo(out, CV_8U);
  return out;
}
}  // namespace

TEST_CASE("adaptive binarization finds parts under a light gradient that defeats Otsu",
          "[vision][binarize]") {
  // Parts on the bright side are brighter than the background on the dark side.
  const std::vector<cv::Rect> parts = {{100, 100, 80, 80}, {600, 300, 80, 80}, {1100, 500, 80, 80}};
  const cv::Mat img = litScene(1280, 720, 60, 240, parts, 0.3);
  const auto adaptive = findRegions(binarize(img, {}));
  REQUIRE(adaptive.size() == parts.size());
  for (const auto& r : adaptive) CHECK(r.area == Approx(6400).epsilon(0.02));

  BinarizeOptions otsu;
  otsu.method = ThresholdMethod::kOtsu;
  const auto global = findRegions(binarize(img, otsu));
  bool all_found = global.size() == parts.size();
  for (const auto& r : global) all_found = all_found && std::abs(r.area - 6400) < 130;
  CHECK_FALSE(all_found);
}

TEST_CASE("a part wider than the default window needs a wider window", "[vision][binarize]") {
  const std::vector<cv::Rect> parts = {{400, 200, 320, 320}};
  const cv::Mat img = litScene(1280, 720, 150, 220, parts, 0.25);
  // The default window (a sixth of 720 px) is narrower than the part: its
  // middle reads as background and the part is no longer one solid region.
  const auto narrow = findRegions(binarize(img, {}));
  const bool whole =
      narrow.size() == 1 && narrow[0].holes == 0 && std::abs(narrow[0].area - 320.0 * 320.0) < 1000;
  CHECK_FALSE(whole);

  BinarizeOptions wide;
  wide.adaptive_window = 480;
  const auto regions = findRegions(binarize(img, wide));
  REQUIRE(regions.size() == 1);
  CHECK(regions[0].area == Approx(320.0 * 320.0).epsilon(0.01));
  CHECK(regions[0].holes == 0);
}

TEST_CASE("an empty, noisy field has no parts", "[vision][binarize]") {
  const cv::Mat img = litScene(640, 480, 120, 200, {}, 1.0, 4.0);
  CHECK(findRegions(binarize(img, {})).empty());
}

TEST_CASE("light parts on a dark background with the other polarity", "[vision][binarize]") {
  cv::Mat img(300, 400, CV_8UC1, cv::Scalar(30));
  img(cv::Rect(50, 50, 60, 40)).setTo(220);
  img(cv::Rect(250, 150, 50, 50)).setTo(200);
  for (auto method :
       {ThresholdMethod::kAdaptive, ThresholdMethod::kOtsu, ThresholdMethod::kFixed}) {
    BinarizeOptions o;
    o.method = method;
    o.polarity = Polarity::kLightOnDark;
    o.fixed_threshold = 128;
    const auto regions = findRegions(binarize(img, o));
    INFO("method " << static_cast<int>(method));
    REQUIRE(regions.size() == 2);
    CHECK(regions[0].area == 2500);
    CHECK(regions[1].area == 2400);
  }
}

TEST_CASE("fixed threshold splits at the given level", "[vision][binarize]") {
  cv::Mat img(10, 10, CV_8UC1, cv::Scalar(200));
  img.at<uint8_t>(2, 2) = 100;
  img.at<uint8_t>(3, 3) = 101;
  BinarizeOptions o;
  o.method = ThresholdMethod::kFixed;
  o.fixed_threshold = 100;
  const cv::Mat mask = binarize(img, o);
  CHECK(mask.at<uint8_t>(2, 2) == 255);
  CHECK(mask.at<uint8_t>(3, 3) == 0);
  CHECK(cv::countNonZero(mask) == 1);
}

TEST_CASE("binarize never writes into the image it is given", "[vision][binarize]") {
  cv::Mat img(100, 100, CV_8UC1, cv::Scalar(30));
  img(cv::Rect(20, 20, 30, 30)).setTo(220);
  const cv::Mat before = img.clone();
  for (auto polarity : {Polarity::kDarkOnLight, Polarity::kLightOnDark}) {
    for (auto method :
         {ThresholdMethod::kAdaptive, ThresholdMethod::kOtsu, ThresholdMethod::kFixed}) {
      BinarizeOptions o;
      o.method = method;
      o.polarity = polarity;
      (void)binarize(img, o);
      CHECK(cv::countNonZero(img != before) == 0);
    }
  }
}

TEST_CASE("the 3x3 mean binarize compares a noisy frame by is cv::blur's to the last bit",
          "[vision][binarize]") {
  // Widths that leave a tail past the sixteen-pixel steps, heights down to
  // one row (both neighbours replicated), levels over the whole range and
  // near its top (sums up to 2295), noise that rounds either way.
  cv::RNG rng(11);
  for (const cv::Size size :
       {cv::Size(16, 1), cv::Size(17, 2), cv::Size(61, 9), cv::Size(1920, 3), cv::Size(333, 40)}) {
    for (const int kind : {0, 1, 2}) {
      cv::Mat grey(size, CV_8UC1);
      if (kind == 0) rng.fill(grey, cv::RNG::UNIFORM, 0, 256);
      if (kind == 1) rng.fill(grey, cv::RNG::UNIFORM, 246, 256);
      if (kind == 2) rng.fill(grey, cv::RNG::NORMAL, 128, 40);
      cv::Mat expected;
      cv::blur(grey, expected, cv::Size(3, 3), cv::Point(-1, -1), cv::BORDER_REPLICATE);
      std::vector<uint16_t> sums(static_cast<size_t>(size.width) + 2);
      cv::Mat mean(size, CV_8UC1);
      for (int y = 0; y < size.height; ++y) {
        meanRow3x3(grey, y, sums.data(), mean.ptr<uint8_t>(y));
      }
      INFO(size << " kind " << kind);
      CHECK(cv::countNonZero(mean != expected) == 0);
    }
  }
}
