// Colour axes: a colour frame projected so that parts of every taught colour
// are dark on their surface, each distinct axis once.
#include <catch2/catch.hpp>

#include <vector>

#include <opencv2/core.hpp>

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
