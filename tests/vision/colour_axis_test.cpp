// Colour axes: a colour frame projected so that parts of every taught colour
// are dark on their surface, each distinct axis once.
#include <catch2/catch.hpp>

#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "picksight/vision/segmentation/colour_axis.hpp"

namespace pv = picksight::vision;

namespace {
const cv::Vec3d kSurface(122, 122, 122);
const cv::Vec3d kGreen(60, 160, 70);
const cv::Vec3d kRed(60, 60, 200);

// A grey surface with a green patch on the left and a red one on the right,
// all of one brightness in grey.
cv::Mat twoPatches() {
  cv::Mat bgr(80, 160, CV_8UC3, cv::Scalar(kSurface[0], kSurface[1], kSurface[2]));
  bgr(cv::Rect(10, 20, 40, 40)).setTo(cv::Scalar(kGreen[0], kGreen[1], kGreen[2]));
  bgr(cv::Rect(110, 20, 40, 40)).setTo(cv::Scalar(kRed[0], kRed[1], kRed[2]));
  return bgr;
}
}  // namespace

TEST_CASE("parts of two colours are both dark in the projection, the surface light",
          "[vision][colour]") {
  const cv::Mat projected =
      pv::projectOnColourAxes(twoPatches(), {{kGreen, kSurface}, {kRed, kSurface}});
  REQUIRE(projected.type() == CV_8UC1);
  CHECK(projected.at<uint8_t>(40, 30) == Approx(pv::kColourPartLevel).margin(2));
  CHECK(projected.at<uint8_t>(40, 130) == Approx(pv::kColourPartLevel).margin(2));
  CHECK(projected.at<uint8_t>(40, 80) == Approx(pv::kColourBackgroundLevel).margin(2));
}

TEST_CASE("types taught in one colour on one surface are projected once", "[vision][colour]") {
  // Fifteen types of one green part, each taught on its own image: their
  // axes differ by the noise of the medians, by a level or two. One
  // projection serves them all (each costs a pass over the frame); the first
  // one taught gives the levels.
  const cv::Mat image = twoPatches();
  const pv::ColourAxis first{kGreen, kSurface};
  const pv::ColourAxis again{kGreen + cv::Vec3d(2, -3, 1), kSurface + cv::Vec3d(-2, 0, 2)};
  const cv::Mat one = pv::projectOnColourAxes(image, {first});
  const cv::Mat both = pv::projectOnColourAxes(image, {first, again});
  CHECK(cv::norm(one, both, cv::NORM_INF) == 0);
  // An axis of another colour still counts.
  const cv::Mat with_red = pv::projectOnColourAxes(image, {first, again, {kRed, kSurface}});
  CHECK(with_red.at<uint8_t>(40, 130) == Approx(pv::kColourPartLevel).margin(2));
}

TEST_CASE("over a whole frame darkened towards its rim a part is set apart by its hue",
          "[vision][colour]") {
  // The surface's colour is read on the rectangle's rim; over a whole frame
  // under a vignette the rim is darker than the lit middle, which the whole
  // colour difference then set apart instead of the part. And with the
  // light falling off across the frame the rim's brightness spreads by
  // more than a third of the part's colour difference, which is no doubt
  // about the part's hue.
  cv::Mat bgr(300, 400, CV_8UC3);
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const double u = (x + 0.5) / bgr.cols - 0.5;
      const double v = (y + 0.5) / bgr.rows - 0.5;
      const double light = (1.0 + 0.5 * u) * (1.0 - 0.6 * (u * u + v * v));
      bgr.at<cv::Vec3b>(y, x) = cv::Vec3b::all(cv::saturate_cast<uint8_t>(kSurface[0] * light));
    }
  }
  cv::circle(bgr, {200, 150}, 25, cv::Scalar(kGreen[0], kGreen[1], kGreen[2]), cv::FILLED);
  cv::Mat noisy;
  bgr.convertTo(noisy, CV_32FC3);
  cv::Mat noise(bgr.size(), CV_32FC3);
  cv::randn(noise, cv::Scalar::all(0), cv::Scalar::all(3));
  noisy += noise;
  noisy.convertTo(bgr, CV_8UC3);
  const auto axis = pv::colourAxisIn(bgr, cv::Rect(0, 0, bgr.cols, bgr.rows));
  REQUIRE(axis.has_value());
  CAPTURE(axis->part, axis->background);
  CHECK(cv::norm(axis->part - kGreen) < 15);
  CHECK(pv::colourSeparatesBetter(*axis));
}
