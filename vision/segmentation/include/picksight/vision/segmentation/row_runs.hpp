// A binary mask as runs of set pixels per row, with the square dilations,
// erosions and differences the grey-level region measurement needs, at a
// cost per run instead of per pixel.
#pragma once

#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/hal/intrin.hpp>

namespace picksight::vision {

// f(x, y) for every non-zero pixel of `mask` (CV_8UC1), row by row, left to
// right (cv::findNonZero's order), sixteen pixels a test where none is set:
// an outline or a ring a pixel or two wide leaves most of its box empty,
// and a test a pixel (findNonZero's, or a loop's) cost a sixth of the
// shadows' level reading and 50 us a blob-search rest test.
template <class F>
void forEachSetPixel(const cv::Mat& mask, F&& f) {
  CV_Assert(mask.type() == CV_8UC1);
  for (int y = 0; y < mask.rows; ++y) {
    const uint8_t* row = mask.ptr<uint8_t>(y);
    int x = 0;
#if CV_SIMD128
    for (; x + 16 <= mask.cols; x += 16) {
      if (!cv::v_check_any(cv::v_load(row + x) != cv::v_setzero_u8())) continue;
      for (int i = x; i < x + 16; ++i) {
        if (row[i] != 0) f(i, y);
      }
    }
#endif
    for (; x < mask.cols; ++x) {
      if (row[x] != 0) f(x, y);
    }
  }
}

// The set pixels of a width x height mask, row by row, as sorted disjoint
// half-open column runs [begin, end). A part's mask has a few runs per row
// whatever its width, so morphology with a square of side 2r + 1 costs
// O(runs x r) here where it costs O(pixels x r) on the mask; the region
// measurement needs four of them per part per band width (see regions.cpp).
// Values; not synchronized (one owner at a time).
class RowRuns {
 public:
  using Run = std::pair<int, int>;  // [first, second) columns

  RowRuns() = default;

  // The runs of the non-zero pixels of `mask` (CV_8UC1).
  static RowRuns ofMask(const cv::Mat& mask);

  int width() const { return width_; }
  int height() const { return height_; }
  // Number of set pixels.
  long long count() const;

  // cv::dilate with a (2r+1)-square and OpenCV's default border (nothing
  // set outside the box).
  RowRuns dilated(int r) const;
  // cv::erode with a (2r+1)-square and OpenCV's default border (everything
  // set outside the box, so pixels at the box's edge are not eroded by it).
  RowRuns eroded(int r) const;
  // The pixels set here and not in `other` (same size).
  RowRuns minus(const RowRuns& other) const;
  // The 8-connected part of the set that holds pixel `seed` (nothing when
  // `seed` is not set).
  RowRuns connectedTo(cv::Point seed) const;

  // f(y, begin, end) for every run, rows in order, runs left to right.
  template <class F>
  void forEachRun(F&& f) const {
    for (int y = 0; y < height_; ++y) {
      for (int i = first_[static_cast<size_t>(y)]; i < first_[static_cast<size_t>(y) + 1]; ++i) {
        const Run& run = runs_[static_cast<size_t>(i)];
        f(y, run.first, run.second);
      }
    }
  }

  // A mask of the runs (CV_8UC1, 255 where set): for tests and drawing.
  cv::Mat toMask() const;

 private:
  RowRuns(int width, int height) : width_(width), height_(height) {
    first_.reserve(static_cast<size_t>(height) + 1);
    first_.push_back(0);
  }
  // Writing a result: room for `most` runs, written through the pointer
  // returned, row after row, each row's runs sorted, disjoint and not
  // touching (the one form of a set, so equal sets are equal lists);
  // endRow(put) closes a row, endRuns(put) the whole.
  Run* startRuns(size_t most) {
    runs_.resize(most);
    return runs_.data();
  }
  void endRow(const Run* put) { first_.push_back(static_cast<int>(put - runs_.data())); }
  void endRuns(const Run* put) { runs_.resize(static_cast<size_t>(put - runs_.data())); }
  const Run* rowBegin(int y) const { return runs_.data() + first_[static_cast<size_t>(y)]; }
  const Run* rowEnd(int y) const { return runs_.data() + first_[static_cast<size_t>(y) + 1]; }
  // One 3x3 step of dilated() and eroded().
  RowRuns dilatedByOne() const;
  RowRuns erodedByOne() const;
  // `step` applied r times (a copy for r <= 0).
  RowRuns repeated(int r, RowRuns (RowRuns::*step)() const) const;

  int width_ = 0;
  int height_ = 0;
  std::vector<int> first_;  // runs of row y: runs_[first_[y] .. first_[y + 1])
  std::vector<Run> runs_;
};

}  // namespace picksight::vision
