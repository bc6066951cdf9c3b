// Dilation by a disc as maxima of row runs (see disc_morphology.hpp).
#include "picksight/vision/segmentation/disc_morphology.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

namespace picksight::vision {

cv::Mat discElement(int radius) {
  return cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
}

namespace {
// Up to this radius OpenCV's own filter is as fast or faster: on a part's
// box (286 x 300), one thread, buffers kept, OpenCV 28 / 50 / 87 / 140 /
// 188 / 2310 us at radius 2 / 3 / 4 / 5 / 6 / 20, these runs 36 / 42 / 52 /
// 58 / 68 / 190 us.
constexpr int kOwnUpTo = 2;

// The half-width of each of the element's runs, row by row (-1: a row with
// none), read from OpenCV's own element so that the pixels are its.
std::vector<int> halfWidthsOf(int radius) {
  const cv::Mat e = discElement(radius);
  std::vector<int> half(static_cast<size_t>(e.rows), -1);
  for (int y = 0; y < e.rows; ++y) {
    const uint8_t* row = e.ptr<uint8_t>(y);
    const uint8_t* end = row + e.cols;
    const uint8_t* first = std::find_if(row, end, [](uint8_t v) { return v != 0; });
    if (first == end) continue;
    const auto begin = static_cast<int>(first - row);
    // One run, centred: what the maxima below assume.
    const int last = 2 * radius - begin;
    CV_Assert(last < e.cols &&
              std::all_of(row + begin, row + last + 1, [](uint8_t v) { return v != 0; }) &&
              std::none_of(row + last + 1, end, [](uint8_t v) { return v != 0; }));
    half[static_cast<size_t>(y)] = radius - begin;
  }
  return half;
}

// Radii whose half-widths are made once, on first use, rather than from a
// new element at every call: the shadow cut dilates seven times a shadowed
// part, by radii of 3 to 8 (the lens's blur widens them).
constexpr int kKeptRadii = 16;

std::vector<int> runHalfWidths(int radius) {
  static const std::vector<std::vector<int>> kept = [] {
    std::vector<std::vector<int>> all;
    for (int r = 0; r <= kKeptRadii; ++r) all.push_back(halfWidthsOf(r));
    return all;
  }();
  return radius <= kKeptRadii ? kept[static_cast<size_t>(radius)] : halfWidthsOf(radius);
}

// The dilation of `inner` (a rectangle of `image`) by the disc, into dst;
// `image` holds inner's neighbours as far as they are to be read. Each step
// is one cv::max over whole images (OpenCV's vector code): hand-written
// 16-byte loops fusing the steps were slower (radius 3: 48 us against 42).
void dilateInner(const cv::Mat& image, const cv::Rect& inner, int radius, cv::Mat& dst) {
  const std::vector<int> half = runHalfWidths(radius);
  const int reach = *std::max_element(half.begin(), half.end());
  const int rows = image.rows;
  // The image with `reach` columns of zeros either side: a run reaching
  // past the image's edge reads zeros, which change no maximum (OpenCV's
  // default border for a dilation).
  const int width = image.cols + 2 * reach;
  cv::Mat padded = cv::Mat::zeros(rows, width, CV_8UC1);
  image.copyTo(padded(cv::Rect(reach, 0, image.cols, rows)));
  // levels[k]: at column x the maximum of padded's columns x to x + 2^k - 1,
  // for x up to width - 2^k (the columns past it are not written).
  std::vector<cv::Mat> levels{padded};
  // Per half-width w: at inner's column x the maximum of the image's
  // columns x - w to x + w, in every row of the image.
  std::vector<cv::Mat> runs(static_cast<size_t>(reach) + 1);
  for (const int w : half) {
    if (w < 0 || !runs[static_cast<size_t>(w)].empty()) continue;
    const int from = reach + inner.x - w;  // padded's column of the run's start
    if (w == 0) {
      runs[0] = padded.colRange(from, from + inner.width);
      continue;
    }
    const int n = 2 * w + 1;
    size_t k = 0;
    while ((size_t{2} << k) <= static_cast<size_t>(n)) ++k;
    const int span = 1 << k;  // the largest power of two up to n
    while (levels.size() <= k) {
      const cv::Mat& prev = levels.back();
      const int step = 1 << (levels.size() - 1);
      const int valid = width - 2 * step + 1;
      cv::Mat next(rows, width, CV_8UC1);
      cv::Mat written = next.colRange(0, valid);
      cv::max(prev.colRange(0, valid), prev.colRange(step, step + valid), written);
      levels.push_back(next);
    }
    // Two windows of `span` cover the n columns, overlapping in the middle.
    cv::Mat run(rows, inner.width, CV_8UC1);
    cv::max(levels[k].colRange(from, from + inner.width),
            levels[k].colRange(from + n - span, from + n - span + inner.width), run);
    runs[static_cast<size_t>(w)] = run;
  }
  // Down the disc's rows: dst's row y is the maximum of the runs of image
  // rows inner.y + y + dy that exist. The first row range that covers all
  // of dst sets it; otherwise it starts from zeros.
  dst.create(inner.height, inner.width, CV_8UC1);
  bool set = false;
  for (size_t i = 0; i < half.size(); ++i) {
    if (half[i] < 0) continue;
    const int dy = static_cast<int>(i) - radius;
    const int y0 = std::max(0, -(inner.y + dy));
    const int y1 = std::min(inner.height, rows - (inner.y + dy));
    const cv::Mat& run = runs[static_cast<size_t>(half[i])];
    if (!set && y0 == 0 && y1 == inner.height) {
      run.rowRange(inner.y + dy, inner.y + dy + inner.height).copyTo(dst);
      set = true;
      continue;
    }
    if (!set) {
      dst.setTo(0);
      set = true;
    }
    if (y0 >= y1) continue;
    cv::Mat out = dst.rowRange(y0, y1);
    cv::max(out, run.rowRange(inner.y + dy + y0, inner.y + dy + y1), out);
  }
}

// src with the neighbours a disc of `radius` reads beyond it when src is a
// view into a larger image (as OpenCV's morphology reads them), and where
// src lies within it.
cv::Mat withNeighbours(const cv::Mat& src, int radius, cv::Rect* inner) {
  cv::Size whole;
  cv::Point offset;
  src.locateROI(whole, offset);
  const int top = std::min(radius, offset.y);
  const int left = std::min(radius, offset.x);
  const int bottom = std::min(radius, whole.height - offset.y - src.rows);
  const int right = std::min(radius, whole.width - offset.x - src.cols);
  cv::Mat image = src;
  image.adjustROI(top, bottom, left, right);
  *inner = cv::Rect(left, top, src.cols, src.rows);
  return image;
}

// A mask's rows as bits, 64 pixels a word (pixel x in bit x % 64 of word
// x / 64), `words` a row; the bits past the last column are clear.
struct PackedRows {
  int rows = 0;
  int words = 0;
  std::vector<uint64_t> bits;
  uint64_t* row(int y) { return bits.data() + static_cast<size_t>(y) * static_cast<size_t>(words); }
  const uint64_t* row(int y) const {
    return bits.data() + static_cast<size_t>(y) * static_cast<size_t>(words);
  }
};

// The pixels of `image` that are set (`set` true: non-zero; false: zero),
// packed.
PackedRows pack(const cv::Mat& image, bool set) {
  PackedRows p;
  p.rows = image.rows;
  p.words = (image.cols + 63) / 64;
  p.bits.assign(static_cast<size_t>(p.rows) * static_cast<size_t>(p.words), 0);
  for (int y = 0; y < image.rows; ++y) {
    const uint8_t* in = image.ptr<uint8_t>(y);
    uint64_t* out = p.row(y);
    int x = 0;
#if CV_SIMD128
    // Sixteen pixels' tests a step, as the sign bits of their bytes.
    for (; x + 16 <= image.cols; x += 16) {
      const cv::v_uint8x16 zero = cv::v_load(in + x) == cv::v_setzero_u8();
      const auto lanes = static_cast<uint64_t>(
          static_cast<unsigned>(cv::v_signmask(cv::v_reinterpret_as_s8(zero))) & 0xFFFFu);
      out[x / 64] |= (set ? ~lanes & 0xFFFFu : lanes) << (x % 64);
    }
#endif
    for (; x < image.cols; ++x) {
      const bool on = (in[x] != 0) == set;
      out[x / 64] |= static_cast<uint64_t>(on) << (x % 64);
    }
  }
  return p;
}

// dst = src | src shifted by `d` pixels (d > 0: each bit to d columns
// further right; d < 0: left), over a row of `words` words.
void orShifted(const uint64_t* src, uint64_t* dst, int words, int d) {
  const int whole = std::abs(d) / 64;
  const int part = std::abs(d) % 64;
  for (int i = 0; i < words; ++i) {
    uint64_t v = 0;
    if (d > 0) {
      const int from = i - whole;  // the word whose bits move into word i
      if (from >= 0) v = src[from] << part;
      if (part != 0 && from - 1 >= 0) v |= src[from - 1] >> (64 - part);
    } else {
      const int from = i + whole;
      if (from < words) v = src[from] >> part;
      if (part != 0 && from + 1 < words) v |= src[from + 1] << (64 - part);
    }
    dst[i] |= v;
  }
}

// 0xFF in byte k of entry b where bit k of b is set: eight pixels a look-up.
const std::array<uint64_t, 256>& byteSpread() {
  static const std::array<uint64_t, 256> table = [] {
    std::array<uint64_t, 256> t{};
    for (size_t b = 0; b < t.size(); ++b) {
      for (int k = 0; k < 8; ++k) {
        if ((b >> k) & 1u) t[b] |= uint64_t{0xFF} << (8 * k);
      }
    }
    return t;
  }();
  return table;
}

// The dilation of the pixels of `image` set as `set` says by the disc, over
// `inner` (a rectangle of `image`, which holds inner's neighbours as far as
// they are to be read), into dst as 255 where the dilation is set and 0
// elsewhere (`invert`: the other way round). Rows of bits: each of the
// disc's run widths is the row ORed with itself shifted, and the disc's rows
// are ORed down, a word (64 pixels) at a time.
void dilateBits(const cv::Mat& image, const cv::Rect& inner, int radius, bool set, bool invert,
                cv::Mat& dst) {
  const std::vector<int> half = runHalfWidths(radius);
  const int reach = *std::max_element(half.begin(), half.end());
  const PackedRows packed = pack(image, set);
  const int words = packed.words;
  // widened[w]: the rows dilated along themselves by w either way.
  std::vector<PackedRows> widened(static_cast<size_t>(reach) + 1);
  widened[0] = packed;
  for (int w = 1; w <= reach; ++w) {
    PackedRows& next = widened[static_cast<size_t>(w)];
    next = widened[static_cast<size_t>(w) - 1];
    for (int y = 0; y < packed.rows; ++y) {
      orShifted(packed.row(y), next.row(y), words, w);
      orShifted(packed.row(y), next.row(y), words, -w);
    }
  }
  // Bits past the image's last column are clear in `packed`, so no shift
  // left brings one in; shifts right may set some in the widened rows,
  // which are never copied out (only inner's columns are).
  std::vector<uint64_t> out(static_cast<size_t>(words) + 1);
  std::vector<uint8_t> bytes(static_cast<size_t>(words) * 64 + 8);
  const std::array<uint64_t, 256>& spread = byteSpread();
  dst.create(inner.height, inner.width, CV_8UC1);
  for (int y = 0; y < inner.height; ++y) {
    std::fill(out.begin(), out.end(), 0);
    const int at = inner.y + y;
    for (size_t i = 0; i < half.size(); ++i) {
      const int w = half[i];
      const int from = at + static_cast<int>(i) - radius;
      if (w < 0 || from < 0 || from >= packed.rows) continue;
      const uint64_t* row = widened[static_cast<size_t>(w)].row(from);
      for (int k = 0; k < words; ++k) out[static_cast<size_t>(k)] |= row[k];
    }
    // Bits to bytes for the whole row, then inner's columns copied out.
    for (int k = 0; k < words; ++k) {
      uint64_t v = out[static_cast<size_t>(k)];
      if (invert) v = ~v;
      // A mask's words are mostly all clear or all set (outside the part,
      // inside it): sixty-four bytes at once.
      if (v == 0 || v == ~uint64_t{0}) {
        std::memset(bytes.data() + 64 * k, v == 0 ? 0 : 0xFF, 64);
        continue;
      }
      for (int b = 0; b < 8; ++b) {
        const uint64_t eight = spread[(v >> (8 * b)) & 0xFFu];
        std::memcpy(bytes.data() + 64 * k + 8 * b, &eight, sizeof eight);
      }
    }
    std::memcpy(dst.ptr<uint8_t>(y), bytes.data() + inner.x, static_cast<size_t>(inner.width));
  }
}

// dilateMask (`dilate`) or erodeMask: the erosion is the dilation of the
// unset pixels, complemented (past the image's edge nothing is unset:
// pixels outside take no part).
void morphMask(const cv::Mat& src, cv::Mat& dst, int radius, bool dilate) {
  CV_Assert(src.type() == CV_8UC1 && radius >= 0);
  if (src.empty()) {
    dst.create(src.size(), CV_8UC1);
    return;
  }
  cv::Rect inner;
  const cv::Mat image = withNeighbours(src, radius, &inner);
  if (dst.data == src.data) {
    // Written in place: the result is made aside first (the rows read
    // overlap those written).
    cv::Mat made;
    dilateBits(image, inner, radius, dilate, !dilate, made);
    made.copyTo(dst);
    return;
  }
  dilateBits(image, inner, radius, dilate, !dilate, dst);
}
}  // namespace

void dilateMask(const cv::Mat& src, cv::Mat& dst, int radius) { morphMask(src, dst, radius, true); }

void erodeMask(const cv::Mat& src, cv::Mat& dst, int radius) { morphMask(src, dst, radius, false); }

void dilateDisc(const cv::Mat& src, cv::Mat& dst, int radius) {
  CV_Assert(src.type() == CV_8UC1 && radius >= 0);
  if (radius <= kOwnUpTo || src.empty()) {
    cv::dilate(src, dst, discElement(radius));
    return;
  }
  cv::Rect inner;
  const cv::Mat image = withNeighbours(src, radius, &inner);
  dilateInner(image, inner, radius, dst);
}

void erodeDisc(const cv::Mat& src, cv::Mat& dst, int radius) {
  CV_Assert(src.type() == CV_8UC1 && radius >= 0);
  if (radius <= kOwnUpTo || src.empty()) {
    cv::erode(src, dst, discElement(radius));
    return;
  }
  // The erosion is the complement's dilation, complemented: past the
  // image's edge the complement's zeros are the erosion's border (pixels
  // outside take no part in a minimum either).
  cv::Rect inner;
  cv::Mat inverse;
  cv::bitwise_not(withNeighbours(src, radius, &inner), inverse);
  dilateInner(inverse, inner, radius, dst);
  cv::bitwise_not(dst, dst);
}

}  // namespace picksight::vision
