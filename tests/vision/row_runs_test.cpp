// Row-run morphology against OpenCV's on masks nobody drew by hand: random
// blobs, speckle, shapes at the box's edges, every radius the region
// measurement uses.
#include <catch2/catch.hpp>

#include <array>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "picksight/vision/segmentation/row_runs.hpp"

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

// The runs as (row, begin, end) triples, in order.
std::vector<std::array<int, 3>> listOf(const RowRuns& runs) {
  std::vector<std::array<int, 3>> list;
  runs.forEachRun([&](int y, int a, int b) { list.push_back({y, a, b}); });
  return list;
}

// Equal sets must be equal run lists (maximal runs, no two touching): the
// region measurement sums over runs, and its sums must not depend on how a
// set was made.
bool canonical(const RowRuns& runs) {
  return listOf(runs) == listOf(RowRuns::ofMask(runs.toMask()));
}
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

TEST_CASE("row-run morphology gives maximal runs whatever the steps") {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 20; ++trial) {
    const cv::Mat a = randomMask(rng, 70 + trial, 50);
    const cv::Mat b = randomMask(rng, 70 + trial, 50);
    const RowRuns runs = RowRuns::ofMask(a);
    for (int r = 1; r <= 4; ++r) {
      INFO("trial " << trial << " radius " << r);
      CHECK(canonical(runs.dilated(r)));
      CHECK(canonical(runs.eroded(r)));
      // Step by step and at once are the same set and the same list.
      CHECK(listOf(runs.eroded(r)) == listOf(runs.eroded(r - 1).eroded(1)));
      CHECK(listOf(runs.dilated(r)) == listOf(runs.dilated(r - 1).dilated(1)));
    }
    CHECK(canonical(runs.minus(RowRuns::ofMask(b))));
    CHECK(canonical(runs.dilated(2).minus(runs.eroded(1))));
  }
}

TEST_CASE("row-run morphology on boxes one pixel wide or high") {
  // Rows and columns with no neighbour on one side or both: the box's
  // edges bound every step.
  std::mt19937 rng(29);
  const cv::Size sizes[] = {{1, 1}, {1, 7}, {9, 1}, {2, 2}, {3, 2}, {2, 5}};
  for (const cv::Size& size : sizes) {
    for (int trial = 0; trial < 8; ++trial) {
      cv::Mat mask(size, CV_8UC1);
      for (int y = 0; y < size.height; ++y) {
        for (int x = 0; x < size.width; ++x) mask.at<uint8_t>(y, x) = (rng() % 3) ? 255 : 0;
      }
      const RowRuns runs = RowRuns::ofMask(mask);
      for (int r = 0; r <= 3; ++r) {
        cv::Mat expected;
        INFO("size " << size << " trial " << trial << " radius " << r);
        cv::dilate(mask, expected, square(r));
        CHECK(same(runs.dilated(r).toMask(), expected));
        cv::erode(mask, expected, square(r));
        CHECK(same(runs.eroded(r).toMask(), expected));
      }
    }
  }
}

TEST_CASE("the runs connected to a pixel are its 8-connected component") {
  std::mt19937 rng(31);
  for (int trial = 0; trial < 20; ++trial) {
    const cv::Mat mask = randomMask(rng, 60 + trial * 5, 40 + trial * 3);
    const RowRuns runs = RowRuns::ofMask(mask);
    cv::Mat labels;
    cv::connectedComponents(mask, labels, 8, CV_32S);
    std::vector<cv::Point> set;
    cv::findNonZero(mask, set);
    for (int k = 0; k < 5 && !set.empty(); ++k) {
      const cv::Point seed = set[rng() % set.size()];
      const RowRuns part = runs.connectedTo(seed);
      INFO("trial " << trial << " seed " << seed);
      CHECK(same(part.toMask(), labels == labels.at<int>(seed)));
      CHECK(canonical(part));
    }
    // A seed on the background, or outside the box, reaches nothing.
    cv::Point empty(-1, -1);
    for (int y = 0; y < mask.rows && empty.x < 0; ++y) {
      for (int x = 0; x < mask.cols && empty.x < 0; ++x) {
        if (mask.at<uint8_t>(y, x) == 0) empty = cv::Point(x, y);
      }
    }
    if (empty.x >= 0) CHECK(runs.connectedTo(empty).count() == 0);
    CHECK(runs.connectedTo(cv::Point(0, mask.rows)).count() == 0);
  }
}

TEST_CASE("runs touching only at a corner are one component") {
  // Two diagonal staircases and a pixel alone: 8-connectivity joins corners.
  cv::Mat mask(6, 8, CV_8UC1, cv::Scalar(0));
  for (int i = 0; i < 4; ++i) mask.at<uint8_t>(i, i) = 255;
  mask.at<uint8_t>(0, 6) = 255;
  mask.at<uint8_t>(5, 7) = 255;
  const RowRuns runs = RowRuns::ofMask(mask);
  CHECK(runs.connectedTo(cv::Point(0, 0)).count() == 4);
  CHECK(runs.connectedTo(cv::Point(3, 3)).count() == 4);
  CHECK(runs.connectedTo(cv::Point(6, 0)).count() == 1);
  CHECK(runs.connectedTo(cv::Point(7, 5)).count() == 1);
}

TEST_CASE("row runs take any non-zero level for set") {
  // Levels 1 and 128 as well as 255, with runs starting and ending at every
  // place within eight pixels.
  std::mt19937 rng(37);
  const uint8_t levels[] = {0, 1, 128, 255};
  for (int trial = 0; trial < 20; ++trial) {
    cv::Mat mask(9, 5 + trial * 3, CV_8UC1);
    for (int y = 0; y < mask.rows; ++y) {
      for (int x = 0; x < mask.cols; ++x) {
        mask.at<uint8_t>(y, x) = rng() % 3 == 0 ? levels[rng() % 4] : levels[(y + x / 5) % 2 * 3];
      }
    }
    INFO("trial " << trial);
    CHECK(same(RowRuns::ofMask(mask).toMask(), mask != 0));
    CHECK(RowRuns::ofMask(mask).count() == cv::countNonZero(mask));
  }
}
