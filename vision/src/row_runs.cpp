// Binary morphology on row runs (see row_runs.hpp).
#include "picksight/vision/row_runs.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>

namespace picksight::vision {

namespace {
// The first pixel of `row` at or after x whose "is set" differs from `set`
// (w when none). Eight pixels are skipped at a time while all of them are
// on the same side: a part's box is mostly long stretches of one or the
// other.
int nextChange(const uint8_t* row, int x, int w, bool set) {
  const uint64_t same = set ? ~uint64_t{0} : 0;
  for (; x + 8 <= w; x += 8) {
    uint64_t eight = 0;
    std::memcpy(&eight, row + x, sizeof eight);
    if (eight != same) break;
  }
  for (; x < w && (row[x] != 0) == set; ++x) {
  }
  return x;
}

// One row's runs, each narrowed by one pixel at both ends except at the
// box's edges (the erosion border counts as set), read one at a time.
struct NarrowedRow {
  const RowRuns::Run* run;
  const RowRuns::Run* end;
  int width;

  // The next non-empty narrowed run, false when none is left.
  bool next(int* a, int* b) {
    for (; run != end; ++run) {
      *a = run->first > 0 ? run->first + 1 : 0;
      *b = run->second < width ? run->second - 1 : width;
      if (*a < *b) {
        ++run;
        return true;
      }
    }
    return false;
  }
};
}  // namespace

RowRuns RowRuns::ofMask(const cv::Mat& mask) {
  CV_Assert(mask.type() == CV_8UC1);
  RowRuns runs(mask.cols, mask.rows);
  for (int y = 0; y < mask.rows; ++y) {
    const uint8_t* m = mask.ptr<uint8_t>(y);
    for (int a = nextChange(m, 0, mask.cols, false); a < mask.cols;) {
      const int b = nextChange(m, a, mask.cols, true);
      runs.runs_.emplace_back(a, b);
      a = nextChange(m, b, mask.cols, false);
    }
    runs.endRow();
  }
  return runs;
}

long long RowRuns::count() const {
  long long n = 0;
  for (const Run& run : runs_) n += run.second - run.first;
  return n;
}

RowRuns RowRuns::dilated(int r) const {
  if (r <= 0) return *this;
  // A (2r+1)-square is r 3x3 squares one after another.
  RowRuns out = dilatedByOne();
  for (int step = 1; step < r; ++step) out = out.dilatedByOne();
  return out;
}

RowRuns RowRuns::dilatedByOne() const {
  // A 3x3 dilation is each row joined with its two neighbours, every run
  // widened by one: a merge of three sorted lists by start column, widening
  // and joining touching runs on the way (widening keeps the order).
  RowRuns out(width_, height_);
  out.runs_.reserve(runs_.size() + static_cast<size_t>(height_) * 2);
  for (int y = 0; y < height_; ++y) {
    const Run* at[3] = {rowBegin(y), nullptr, nullptr};
    const Run* end[3] = {rowEnd(y), nullptr, nullptr};
    if (y > 0) {
      at[1] = rowBegin(y - 1);
      end[1] = rowEnd(y - 1);
    }
    if (y + 1 < height_) {
      at[2] = rowBegin(y + 1);
      end[2] = rowEnd(y + 1);
    }
    bool open = false;
    int a = 0;
    int b = 0;
    for (;;) {
      int pick = -1;
      for (int k = 0; k < 3; ++k) {
        if (at[k] != end[k] && (pick < 0 || at[k]->first < at[pick]->first)) pick = k;
      }
      if (pick < 0) break;
      const int ra = std::max(0, at[pick]->first - 1);
      const int rb = std::min(width_, at[pick]->second + 1);
      ++at[pick];
      if (open && ra <= b) {
        b = std::max(b, rb);
      } else {
        if (open) out.runs_.emplace_back(a, b);
        a = ra;
        b = rb;
        open = true;
      }
    }
    if (open) out.runs_.emplace_back(a, b);
    out.endRow();
  }
  return out;
}

RowRuns RowRuns::eroded(int r) const {
  if (r <= 0) return *this;
  // A (2r+1)-square is r 3x3 squares one after another, and that holds
  // with OpenCV's border too: a pixel beyond the box's edge is never less
  // set than the nearest one inside after a step.
  RowRuns out = erodedByOne();
  for (int step = 1; step < r; ++step) out = out.erodedByOne();
  return out;
}

RowRuns RowRuns::erodedByOne() const {
  // Narrow each row by one, then keep what the row and its two neighbours
  // all keep; rows beyond the box count as set (OpenCV's default erosion
  // border), so they take nothing away.
  RowRuns out(width_, height_);
  out.runs_.reserve(runs_.size());
  for (int y = 0; y < height_; ++y) {
    NarrowedRow rows[3] = {
        {rowBegin(y), rowEnd(y), width_}, {nullptr, nullptr, width_}, {nullptr, nullptr, width_}};
    int count = 1;
    if (y > 0) rows[count++] = {rowBegin(y - 1), rowEnd(y - 1), width_};
    if (y + 1 < height_) rows[count++] = {rowBegin(y + 1), rowEnd(y + 1), width_};
    // The current run of each row; the intersection advances whichever
    // ends first.
    int a[3];
    int b[3];
    bool done = false;
    for (int k = 0; k < count && !done; ++k) done = !rows[k].next(&a[k], &b[k]);
    while (!done) {
      int lo = a[0];
      int hi = b[0];
      int first_end = 0;
      for (int k = 1; k < count; ++k) {
        lo = std::max(lo, a[k]);
        if (b[k] < hi) {
          hi = b[k];
          first_end = k;
        }
      }
      if (lo < hi) out.runs_.emplace_back(lo, hi);
      done = !rows[first_end].next(&a[first_end], &b[first_end]);
    }
    out.endRow();
  }
  return out;
}

RowRuns RowRuns::minus(const RowRuns& other) const {
  CV_Assert(other.width_ == width_ && other.height_ == height_);
  RowRuns out(width_, height_);
  out.runs_.reserve(runs_.size() + runs_.size() / 2);
  for (int y = 0; y < height_; ++y) {
    const Run* cut = other.rowBegin(y);
    const Run* cut_end = other.rowEnd(y);
    for (const Run* run = rowBegin(y); run != rowEnd(y); ++run) {
      int a = run->first;
      const int b = run->second;
      while (cut != cut_end && cut->second <= a) ++cut;
      for (const Run* c = cut; c != cut_end && c->first < b; ++c) {
        if (c->first > a) out.runs_.emplace_back(a, c->first);
        a = std::max(a, c->second);
      }
      if (a < b) out.runs_.emplace_back(a, b);
    }
    out.endRow();
  }
  return out;
}

cv::Mat RowRuns::toMask() const {
  cv::Mat mask(height_, width_, CV_8UC1, cv::Scalar(0));
  forEachRun([&](int y, int a, int b) {
    std::memset(mask.ptr<uint8_t>(y) + a, 255, static_cast<size_t>(b - a));
  });
  return mask;
}

}  // namespace picksight::vision
