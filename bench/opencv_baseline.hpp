// The plain OpenCV passes PickSight's vision pass is measured against, and the
// order and statistics the benchmarks time them with. Header-only: bench code.
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <functional>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace picksight::bench {

// The competent pass, the baseline: Otsu, one boundary trace that keeps holes
// (RETR_CCOMP: outer boundaries on top, their holes as children), and each
// region's area and centroid from the moments of its outer boundary less
// those of its holes. What a vision engineer writes with OpenCV to find dark
// parts, and what PickSight's own pass is built on (it adds the adaptive
// threshold and sub-pixel grey-level moments). Returns a value to keep.
inline double competentOpenCvPass(const cv::Mat& grey) {
  cv::Mat mask;
  cv::threshold(grey, mask, 0, 255, cv::THRESH_BINARY_INV | cv::THRESH_OTSU);
  std::vector<std::vector<cv::Point>> contours;
  std::vector<cv::Vec4i> hierarchy;
  cv::findContours(mask, contours, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE);
  double sink = 0;
  for (size_t i = 0; i < contours.size(); ++i) {
    if (hierarchy[i][3] >= 0) continue;  // a hole, counted with its region
    cv::Moments m = cv::moments(contours[i]);
    for (int h = hierarchy[i][2]; h >= 0; h = hierarchy[static_cast<size_t>(h)][0]) {
      const cv::Moments hole = cv::moments(contours[static_cast<size_t>(h)]);
      m.m00 -= hole.m00;
      m.m10 -= hole.m10;
      m.m01 -= hole.m01;
    }
    if (m.m00 > 0) sink += m.m10 / m.m00 + m.m01 / m.m00;
  }
  return sink;
}

// The pass the benchmarks timed before: labels the mask as well
// (connectedComponentsWithStats), which the contour trace already gives, so
// it costs about twice the competent pass. Printed as a second line only.
inline double labellingOpenCvPass(const cv::Mat& grey) {
  cv::Mat mask;
  cv::threshold(grey, mask, 0, 255, cv::THRESH_BINARY_INV | cv::THRESH_OTSU);
  cv::Mat labels, st, centroids;
  const int n = cv::connectedComponentsWithStats(mask, labels, st, centroids, 8, CV_32S);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE);
  double sink = n;
  for (const auto& c : contours) sink += cv::moments(c).m00;
  return sink;
}

// The p-th percentile by nearest rank: the smallest sample with at least p %
// of the samples at or below it (p99 of 200 samples: the 198th smallest).
// Meaningful for p99 only from 100 samples on.
inline double nearestRank(std::vector<double> samples, double p) {
  if (samples.empty()) return 0;
  std::sort(samples.begin(), samples.end());
  const auto rank = static_cast<size_t>(std::ceil(p / 100.0 * static_cast<double>(samples.size())));
  return samples[std::min(samples.size(), std::max<size_t>(rank, 1)) - 1];
}

// The milliseconds `pass` takes, once.
inline double elapsedMs(const std::function<void()>& pass) {
  const auto t0 = std::chrono::steady_clock::now();
  pass();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Times `passes` on one frame, each into its own list of milliseconds, the
// one that runs first turning with `turn` (the frame's index): a pass that
// always ran first would pay for cold caches, or always profit from warm ones.
template <size_t N>
void timeInTurn(size_t turn, const std::array<std::function<void()>, N>& passes,
                std::array<std::vector<double>*, N> ms) {
  for (size_t k = 0; k < N; ++k) {
    const size_t which = (turn + k) % N;
    const auto t0 = std::chrono::steady_clock::now();
    passes[which]();
    const auto t1 = std::chrono::steady_clock::now();
    ms[which]->push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
}

}  // namespace picksight::bench
