// Row-run morphology against OpenCV's on masks nobody drew by hand: random
// blobs, speckle, shapes at the box's edges, every radius the region
// measurement uses.
#include <catch2/catch.hpp>

#include <opencv2/imgproc.hpp>
#include <random>

#include "picksight/vision/row_runs.hpp"

using picksight::vision::RowRuns;

namespace {
cv::Mat square(int r) {
  return cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * r + 1, 2 * r + 1));
}

// Random discs, rectangles, lines and speckle, some cut by the box's edges.
cv::Mat randomMask(std::mt19937& rng, int width, int height) {
  cv::Mat mask(height, width, CV_8UC1, cv::Scalar(0));
  std::uniform_int_distribution<int> x(-10, width + 10);
  std::uniform_int_distribution<int> y(-10, height + 10);
  std::uniform_int_distribution<int> size(1, 40);
  std::uniform_int_distribution<int> kind(0, 3);
  for (int i = 0; i < 12; ++i) {
    const cv::Point p(x(rng), y(rng));
    const int s = size(rng);
    switch (kind(rng)) {
      case 0:
        cv::circle(mask, p, s, cv::Scalar(255), cv::FILLED);
        break;
      case 1:
        cv::rectangle(mask, cv::Rect(p, cv::Size(s, size(rng))), cv::Scalar(255), cv::FILLED);
        break;
      case 2:
        cv::line(mask, p, cv::Point(x(rng), y(rng)), cv::Scalar(255), 1 + s % 3);
        break;
      default:
        // A hole punched in whatever is there.
        cv::circle(mask, p, s / 2, cv::Scalar(0), cv::FILLED);
        break;
    }
  }
  // Speckle: isolated pixels both ways.
  std::uniform_int_distribution<int> px(0, width - 1);
  std::uniform_int_distribution<int> py(0, height - 1);
  for (int i = 0; i < 30; ++i) mask.at<uint8_t>(py(rng), px(rng)) ^= 255;
  return mask;
}

bool same(const cv::Mat& a, const cv::Mat& b) { return cv::countNonZero(a != b) == 0; }
}  // namespace

TEST_CASE("row runs give back the mask they were made from") {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const cv::Mat mask = randomMask(rng, 37 + trial * 13, 23 + trial * 7);
    const RowRuns runs = RowRuns::ofMask(mask);
    CHECK(same(runs.toMask(), mask));
    CHECK(runs.count() == cv::countNonZero(mask));
  }
}

TEST_CASE("row-run dilation and erosion equal OpenCV's with its default borders") {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 30; ++trial) {
    const int width = 20 + static_cast<int>(rng() % 200);
    const int height = 15 + static_cast<int>(rng() % 150);
    const cv::Mat mask = randomMask(rng, width, height);
    const RowRuns runs = RowRuns::ofMask(mask);
    for (int r = 0; r <= 8; ++r) {
      cv::Mat expected;
      cv::dilate(mask, expected, square(r));
      INFO("trial " << trial << " dilation radius " << r);
      CHECK(same(runs.dilated(r).toMask(), expected));
      cv::erode(mask, expected, square(r));
      INFO("trial " << trial << " erosion radius " << r);
      CHECK(same(runs.eroded(r).toMask(), expected));
    }
  }
}

TEST_CASE("row-run difference equals the masks' difference") {
  std::mt19937 rng(17);
  for (int trial = 0; trial < 30; ++trial) {
    const cv::Mat a = randomMask(rng, 90, 60);
    const cv::Mat b = randomMask(rng, 90, 60);
    cv::Mat expected;
    cv::subtract(a, b, expected);  // 255 - 255 saturates at 0: a and not b
    CHECK(same(RowRuns::ofMask(a).minus(RowRuns::ofMask(b)).toMask(), expected));
  }
}

TEST_CASE("row runs of an empty mask and of a full one") {
  const cv::Mat empty(10, 16, CV_8UC1, cv::Scalar(0));
  const cv::Mat full(10, 16, CV_8UC1, cv::Scalar(255));
  CHECK(RowRuns::ofMask(empty).dilated(3).count() == 0);
  CHECK(RowRuns::ofMask(full).eroded(3).count() == 160);  // the border counts as set
  CHECK(RowRuns::ofMask(full).minus(RowRuns::ofMask(full)).count() == 0);
}
