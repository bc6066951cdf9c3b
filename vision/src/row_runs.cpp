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

// Sorted disjoint runs of the union of `runs` (sorted by start, may overlap
// or touch).
void mergeInto(std::vector<RowRuns::Run>& runs, std::vector<RowRuns::Run>* out) {
  out->clear();
  for (const auto& run : runs) {
    if (!out->empty() && run.first <= out->back().second) {
      out->back().second = std::max(out->back().second, run.second);
    } else {
      out->push_back(run);
    }
  }
}

// The intersection of two sorted disjoint run lists.
void intersect(const std::vector<RowRuns::Run>& a, const RowRuns::Run* b, const RowRuns::Run* b_end,
               std::vector<RowRuns::Run>* out) {
  out->clear();
  size_t i = 0;
  while (i < a.size() && b != b_end) {
    const int lo = std::max(a[i].first, b->first);
    const int hi = std::min(a[i].second, b->second);
    if (lo < hi) out->emplace_back(lo, hi);
    if (a[i].second < b->second) {
      ++i;
    } else {
      ++b;
    }
  }
}
}  // namespace

RowRuns RowRuns::ofMask(const cv::Mat& mask) {
  CV_Assert(mask.type() == CV_8UC1);
  RowRuns runs(mask.cols, mask.rows);
  std::vector<Run> row;
  for (int y = 0; y < mask.rows; ++y) {
    const uint8_t* m = mask.ptr<uint8_t>(y);
    row.clear();
    for (int a = nextChange(m, 0, mask.cols, false); a < mask.cols;) {
      const int b = nextChange(m, a, mask.cols, true);
      row.emplace_back(a, b);
      a = nextChange(m, b, mask.cols, false);
    }
    runs.pushRow(row);
  }
  return runs;
}

void RowRuns::pushRow(const std::vector<Run>& row) {
  runs_.insert(runs_.end(), row.begin(), row.end());
  first_.push_back(static_cast<int>(runs_.size()));
}

long long RowRuns::count() const {
  long long n = 0;
  for (const Run& run : runs_) n += run.second - run.first;
  return n;
}

RowRuns RowRuns::horizontally(int r) const {
  RowRuns out(width_, height_);
  out.runs_.reserve(runs_.size());
  std::vector<Run> row;
  std::vector<Run> merged;
  for (int y = 0; y < height_; ++y) {
    row.clear();
    for (const Run* run = rowBegin(y); run != rowEnd(y); ++run) {
      int a = run->first;
      int b = run->second;
      if (r >= 0) {
        a = std::max(0, a - r);
        b = std::min(width_, b + r);
      } else {
        if (a > 0) a -= r;
        if (b < width_) b += r;
      }
      if (a < b) row.emplace_back(a, b);
    }
    // Widened runs may now touch or overlap; narrowed ones stay disjoint.
    mergeInto(row, &merged);
    out.pushRow(merged);
  }
  return out;
}

RowRuns RowRuns::dilated(int r) const {
  if (r <= 0) return *this;
  // A (2r+1)-square is r 3x3 squares one after another, and a 3x3 dilation
  // is each row widened by one and joined with its two neighbours: merges
  // of three sorted lists, no sorting.
  RowRuns out = *this;
  std::vector<Run> joined;
  std::vector<Run> merged;
  for (int step = 0; step < r; ++step) {
    const RowRuns wide = out.horizontally(1);
    RowRuns next(width_, height_);
    next.runs_.reserve(wide.runs_.size());
    for (int y = 0; y < height_; ++y) {
      joined.clear();
      const Run* rows[3][2] = {
          {nullptr, nullptr}, {wide.rowBegin(y), wide.rowEnd(y)}, {nullptr, nullptr}};
      if (y > 0) {
        rows[0][0] = wide.rowBegin(y - 1);
        rows[0][1] = wide.rowEnd(y - 1);
      }
      if (y + 1 < height_) {
        rows[2][0] = wide.rowBegin(y + 1);
        rows[2][1] = wide.rowEnd(y + 1);
      }
      // Three-way merge by start column.
      for (;;) {
        int pick = -1;
        for (int k = 0; k < 3; ++k) {
          if (rows[k][0] == rows[k][1]) continue;
          if (pick < 0 || rows[k][0]->first < rows[pick][0]->first) pick = k;
        }
        if (pick < 0) break;
        joined.push_back(*rows[pick][0]++);
      }
      mergeInto(joined, &merged);
      next.pushRow(merged);
    }
    out = std::move(next);
  }
  return out;
}

RowRuns RowRuns::eroded(int r) const {
  if (r <= 0) return *this;
  // Narrow each row, then keep what all of a row's 2r + 1 neighbours keep;
  // rows beyond the box count as set (OpenCV's default erosion border).
  const RowRuns narrow = horizontally(-r);
  RowRuns out(width_, height_);
  out.runs_.reserve(runs_.size());
  std::vector<Run> kept;
  std::vector<Run> next;
  for (int y = 0; y < height_; ++y) {
    kept.assign(narrow.rowBegin(y), narrow.rowEnd(y));
    for (int yy = std::max(0, y - r); yy <= std::min(height_ - 1, y + r) && !kept.empty(); ++yy) {
      if (yy == y) continue;
      intersect(kept, narrow.rowBegin(yy), narrow.rowEnd(yy), &next);
      kept.swap(next);
    }
    out.pushRow(kept);
  }
  return out;
}

RowRuns RowRuns::minus(const RowRuns& other) const {
  CV_Assert(other.width_ == width_ && other.height_ == height_);
  RowRuns out(width_, height_);
  out.runs_.reserve(runs_.size());
  std::vector<Run> row;
  for (int y = 0; y < height_; ++y) {
    row.clear();
    const Run* cut = other.rowBegin(y);
    const Run* cut_end = other.rowEnd(y);
    for (const Run* run = rowBegin(y); run != rowEnd(y); ++run) {
      int a = run->first;
      const int b = run->second;
      while (cut != cut_end && cut->second <= a) ++cut;
      for (const Run* c = cut; c != cut_end && c->first < b; ++c) {
        if (c->first > a) row.emplace_back(a, c->first);
        a = std::max(a, c->second);
      }
      if (a < b) row.emplace_back(a, b);
    }
    out.pushRow(row);
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
