// Binary morphology on row runs (see row_runs.hpp).
#include "picksight/vision/segmentation/row_runs.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>

namespace picksight::vision {

namespace {
// The first pixel of `row` at or after x whose "is set" differs from `set`
// (w when none). Eight pixels are read at a time: a part's box is mostly
// long stretches of one or the other, and where a word holds a change, its
// first changed byte is found from the word's bits.
int nextChange(const uint8_t* row, int x, int w, bool set) {
  constexpr uint64_t kLow = 0x0101010101010101ULL;
  constexpr uint64_t kHigh = 0x8080808080808080ULL;
  for (; x + 8 <= w; x += 8) {
    uint64_t eight = 0;
    std::memcpy(&eight, row + x, sizeof eight);
    // A bit at the top of each byte that differs; for zero bytes the
    // lowest flag is exact (a borrow only flags bytes above a zero one).
    const uint64_t changed = set ? (eight - kLow) & ~eight & kHigh : eight;
    if (changed != 0) {
#if defined(__GNUC__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
      return x + (__builtin_ctzll(changed) >> 3);
#else
      break;
#endif
    }
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
    runs.first_.push_back(static_cast<int>(runs.runs_.size()));
  }
  return runs;
}

long long RowRuns::count() const {
  long long n = 0;
  for (const Run& run : runs_) n += run.second - run.first;
  return n;
}

RowRuns RowRuns::repeated(int r, RowRuns (RowRuns::*step)() const) const {
  if (r <= 0) return *this;
  RowRuns out = (this->*step)();
  for (int k = 1; k < r; ++k) out = (out.*step)();
  return out;
}

RowRuns RowRuns::dilated(int r) const {
  // A (2r+1)-square is r 3x3 squares one after another.
  return repeated(r, &RowRuns::dilatedByOne);
}

RowRuns RowRuns::dilatedByOne() const {
  // A 3x3 dilation is each row joined with its two neighbours, every run
  // widened by one: a merge of three sorted lists by start column, widening
  // and joining touching runs on the way (widening keeps the order).
  constexpr int kDone = std::numeric_limits<int>::max();
  RowRuns out(width_, height_);
  // A row has at most as many runs as the three it is made of.
  Run* put = out.startRuns(3 * runs_.size());
  for (int y = 0; y < height_; ++y) {
    const Run* at[3] = {rowBegin(y), rowEnd(y), rowEnd(y)};
    const Run* end[3] = {rowEnd(y), rowEnd(y), rowEnd(y)};
    if (y > 0) {
      at[1] = rowBegin(y - 1);
      end[1] = rowEnd(y - 1);
    }
    if (y + 1 < height_) {
      at[2] = rowBegin(y + 1);
      end[2] = rowEnd(y + 1);
    }
    // Each list's next start column, kDone when it is used up.
    int start[3];
    for (int k = 0; k < 3; ++k) start[k] = at[k] != end[k] ? at[k]->first : kDone;
    int a = 0;
    int b = -1;  // no run open
    for (;;) {
      int k = start[0] <= start[1] ? 0 : 1;
      if (start[2] < start[k]) k = 2;
      if (start[k] == kDone) break;
      const int ra = std::max(0, start[k] - 1);
      const int rb = std::min(width_, at[k]->second + 1);
      ++at[k];
      start[k] = at[k] != end[k] ? at[k]->first : kDone;
      if (ra <= b) {
        b = std::max(b, rb);
      } else {
        if (b >= 0) *put++ = {a, b};
        a = ra;
        b = rb;
      }
    }
    if (b >= 0) *put++ = {a, b};
    out.endRow(put);
  }
  out.endRuns(put);
  return out;
}

RowRuns RowRuns::eroded(int r) const {
  // A (2r+1)-square is r 3x3 squares one after another, and that holds
  // with OpenCV's border too: a pixel beyond the box's edge is never less
  // set than the nearest one inside after a step.
  return repeated(r, &RowRuns::erodedByOne);
}

RowRuns RowRuns::erodedByOne() const {
  // Narrow each row by one, then keep what the row and its two neighbours
  // all keep; rows beyond the box count as set (OpenCV's default erosion
  // border), so they take nothing away.
  RowRuns out(width_, height_);
  // Each piece of the intersection ends where a run of one of the three
  // rows ends.
  Run* put = out.startRuns(3 * runs_.size());
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
      if (lo < hi) *put++ = {lo, hi};
      done = !rows[first_end].next(&a[first_end], &b[first_end]);
    }
    out.endRow(put);
  }
  out.endRuns(put);
  return out;
}

RowRuns RowRuns::minus(const RowRuns& other) const {
  CV_Assert(other.width_ == width_ && other.height_ == height_);
  RowRuns out(width_, height_);
  // Each cut splits a run in two at most.
  Run* put = out.startRuns(runs_.size() + other.runs_.size());
  for (int y = 0; y < height_; ++y) {
    const Run* cut = other.rowBegin(y);
    const Run* cut_end = other.rowEnd(y);
    for (const Run* run = rowBegin(y); run != rowEnd(y); ++run) {
      int a = run->first;
      const int b = run->second;
      while (cut != cut_end && cut->second <= a) ++cut;
      for (const Run* c = cut; c != cut_end && c->first < b; ++c) {
        if (c->first > a) *put++ = {a, c->first};
        a = std::max(a, c->second);
      }
      if (a < b) *put++ = {a, b};
    }
    out.endRow(put);
  }
  out.endRuns(put);
  return out;
}

RowRuns RowRuns::connectedTo(cv::Point seed) const {
  // A walk over runs, not pixels: runs of neighbouring rows are 8-connected
  // when they overlap once each is widened by one.
  std::vector<char> reached(runs_.size(), 0);
  std::vector<std::pair<int, int>> pending;  // (run index, row)
  if (seed.y >= 0 && seed.y < height_) {
    for (int i = first_[static_cast<size_t>(seed.y)]; i < first_[static_cast<size_t>(seed.y) + 1];
         ++i) {
      const Run& run = runs_[static_cast<size_t>(i)];
      if (run.first <= seed.x && seed.x < run.second) {
        reached[static_cast<size_t>(i)] = 1;
        pending.emplace_back(i, seed.y);
      }
    }
  }
  while (!pending.empty()) {
    const auto [i, y] = pending.back();
    pending.pop_back();
    const Run run = runs_[static_cast<size_t>(i)];
    for (const int next : {y - 1, y + 1}) {
      if (next < 0 || next >= height_) continue;
      for (int j = first_[static_cast<size_t>(next)]; j < first_[static_cast<size_t>(next) + 1];
           ++j) {
        const Run& other = runs_[static_cast<size_t>(j)];
        if (other.first > run.second) break;
        if (other.second >= run.first && !reached[static_cast<size_t>(j)]) {
          reached[static_cast<size_t>(j)] = 1;
          pending.emplace_back(j, next);
        }
      }
    }
  }
  // Whole runs of a set in their order: the result's runs are maximal too.
  RowRuns out(width_, height_);
  Run* put = out.startRuns(runs_.size());
  for (int y = 0; y < height_; ++y) {
    for (int i = first_[static_cast<size_t>(y)]; i < first_[static_cast<size_t>(y) + 1]; ++i) {
      if (reached[static_cast<size_t>(i)]) *put++ = runs_[static_cast<size_t>(i)];
    }
    out.endRow(put);
  }
  out.endRuns(put);
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
