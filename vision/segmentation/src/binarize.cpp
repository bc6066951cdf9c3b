// Binarization. The adaptive method divides out the illumination: it
// estimates the lit background at low resolution (a maximum filter wider than
// any part erases the dark parts, a blur smooths it), finds with Otsu the
// ratio part/background that separates the two populations, and compares
// every pixel with that ratio of its local background. All heavy work is at
// 1/8 resolution; the full-resolution cost is one block mean and one compare
// against the threshold interpolated on the fly.
#include "picksight/vision/segmentation/binarize.hpp"

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace picksight::vision {
namespace {
constexpr int kReduce = 8;
// Limits of the part/background ratio. Above the upper one, the "parts"
// Otsu finds are sensor noise on an empty field; below the lower one, the
// contrast estimate is unreliable.
constexpr double kMaxRatio = 0.85;
constexpr double kMinRatio = 0.25;
// Two populations whose means lie this many times their pooled spread apart
// are parts and background, however little their contrast (30 grey levels
// on 130 under a front light): the split may then go up to kMaxSeparatedRatio.
// Noise on an empty field, which Otsu also splits in two, gives about 2.7.
constexpr double kMinSeparation = 4.0;
constexpr double kMaxSeparatedRatio = 0.95;

// The mean of every `reduce` x `reduce` block, rounded as cv::resize
// INTER_AREA rounds it (the same image where the blocks tile the frame),
// at a fraction of its cost: the rows of a block are summed 16 pixels at a
// time, then each block's columns, and bands of blocks run on all cores.
void blockMean(const cv::Mat& grey, int reduce, cv::Mat& small) {
  small.create(grey.rows / reduce, grey.cols / reduce, CV_8UC1);
  const float scale = 1.0f / static_cast<float>(reduce * reduce);
  cv::parallel_for_(cv::Range(0, small.rows), [&](const cv::Range& range) {
    std::vector<uint16_t> sums(static_cast<size_t>(grey.cols));
    for (int j = range.start; j < range.end; ++j) {
      std::fill(sums.begin(), sums.end(), 0);
      for (int r = 0; r < reduce; ++r) {
        const uint8_t* g = grey.ptr<uint8_t>(j * reduce + r);
        int x = 0;
#if CV_SIMD128
        for (; x + 16 <= grey.cols; x += 16) {
          cv::v_uint16x8 lo;
          cv::v_uint16x8 hi;
          cv::v_expand(cv::v_load(g + x), lo, hi);
          cv::v_store(sums.data() + x, cv::v_load(sums.data() + x) + lo);
          cv::v_store(sums.data() + x + 8, cv::v_load(sums.data() + x + 8) + hi);
        }
#endif
        for (; x < grey.cols; ++x) sums[static_cast<size_t>(x)] += g[x];
      }
      uint8_t* out = small.ptr<uint8_t>(j);
      for (int i = 0; i < small.cols; ++i) {
        int sum = 0;
        for (int x = i * reduce; x < (i + 1) * reduce; ++x) sum += sums[static_cast<size_t>(x)];
        out[i] = cv::saturate_cast<uint8_t>(static_cast<float>(sum) * scale);
      }
    }
  });
}

// Each row of `small` (CV_16U) linearly interpolated to `width` columns,
// with the geometry of cv::resize (pixel centres, edges clamped) and
// weights in 1/16.
cv::Mat widen(const cv::Mat& small, int width) {
  std::vector<int> x0(static_cast<size_t>(width));
  std::vector<int> w1(static_cast<size_t>(width));
  const double scale = static_cast<double>(small.cols) / width;
  for (int x = 0; x < width; ++x) {
    const double sx = std::max(0.0, (x + 0.5) * scale - 0.5);
    x0[static_cast<size_t>(x)] = std::min(static_cast<int>(sx), small.cols - 1);
    w1[static_cast<size_t>(x)] =
        static_cast<int>(std::lround((sx - x0[static_cast<size_t>(x)]) * 16));
  }
  // The last column repeated once more: the right neighbour of every column
  // exists, and past the last pixel centre the threshold stays level.
  cv::Mat padded;
  cv::copyMakeBorder(small, padded, 0, 0, 0, 1, cv::BORDER_REPLICATE);
  cv::Mat wide(small.rows, width, CV_16U);
  cv::parallel_for_(cv::Range(0, small.rows), [&](const cv::Range& range) {
    for (int y = range.start; y < range.end; ++y) {
      const uint16_t* in = padded.ptr<uint16_t>(y);
      uint16_t* out = wide.ptr<uint16_t>(y);
      for (size_t x = 0; x < x0.size(); ++x) {
        const int a = x0[x];
        out[x] = static_cast<uint16_t>((in[a] * (16 - w1[x]) + in[a + 1] * w1[x] + 8) >> 4);
      }
    }
  });
  return wide;
}

// out = 255 where grey < the threshold interpolated between rows a and b
// (1/16 levels, weights w0 + w1 = 16), else 0. In 1/256 levels the sum
// cannot overflow 16 bits (4080 * 16); the half level added to the grey
// level makes it a compare against the rounded threshold, as a compare
// with an 8-bit threshold image was.
void compareRow(const uint8_t* grey, const uint16_t* a, const uint16_t* b, int w0, int w1,
                uint8_t* out, int n) {
  int x = 0;
#if CV_SIMD128
  const cv::v_uint16x8 vw0 = cv::v_setall_u16(static_cast<uint16_t>(w0));
  const cv::v_uint16x8 vw1 = cv::v_setall_u16(static_cast<uint16_t>(w1));
  const cv::v_uint16x8 half = cv::v_setall_u16(128);
  for (; x + 16 <= n; x += 16) {
    cv::v_uint16x8 g0;
    cv::v_uint16x8 g1;
    cv::v_expand(cv::v_load(grey + x), g0, g1);
    const cv::v_uint16x8 t0 =
        cv::v_mul_wrap(cv::v_load(a + x), vw0) + cv::v_mul_wrap(cv::v_load(b + x), vw1);
    const cv::v_uint16x8 t1 =
        cv::v_mul_wrap(cv::v_load(a + x + 8), vw0) + cv::v_mul_wrap(cv::v_load(b + x + 8), vw1);
    const cv::v_uint16x8 m0 = (cv::v_shl<8>(g0) | half) < t0;
    const cv::v_uint16x8 m1 = (cv::v_shl<8>(g1) | half) < t1;
    cv::v_store(out + x, cv::v_pack(m0, m1));
  }
#endif
  for (; x < n; ++x) {
    const int t = a[x] * w0 + b[x] * w1;
    out[x] = ((grey[x] << 8) | 128) < t ? 255 : 0;
  }
}

cv::Mat adaptive(const cv::Mat& grey, int window) {
  const int reduce = std::min({kReduce, std::max(1, grey.cols / 16), std::max(1, grey.rows / 16)});
  cv::Mat small;
  if (grey.cols % reduce == 0 && grey.rows % reduce == 0) {
    blockMean(grey, reduce, small);
  } else {
    cv::resize(grey, small,
               cv::Size(std::max(1, grey.cols / reduce), std::max(1, grey.rows / reduce)), 0, 0,
               cv::INTER_AREA);
  }
  const int k = std::max(3, (window / reduce) | 1);
  cv::Mat background;
  cv::dilate(small, background, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)),
             cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  cv::blur(background, background, cv::Size(k, k), cv::Point(-1, -1), cv::BORDER_REPLICATE);

  // Ratio image at low resolution, 200 = background level.
  cv::Mat small_f;
  cv::Mat background_f;
  small.convertTo(small_f, CV_32F);
  background.convertTo(background_f, CV_32F);
  cv::Mat ratio;
  cv::divide(small_f, cv::max(background_f, 1.0f), ratio, 200.0);
  cv::Mat ratio8;
  ratio.convertTo(ratio8, CV_8U);
  cv::Mat upper;
  const double otsu = cv::threshold(ratio8, upper, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
  // Otsu's level is the first of a flat optimum: with two clean populations it
  // sits on the edge of the darker one. Split halfway between the two class
  // means instead, where noise on either side is least likely to cross.
  double k_ratio = kMaxRatio;
  const int bright = cv::countNonZero(upper);
  if (bright > 0 && bright < upper.rows * upper.cols) {
    cv::Scalar mean_bright;
    cv::Scalar sd_bright;
    cv::Scalar mean_dark;
    cv::Scalar sd_dark;
    cv::meanStdDev(ratio8, mean_bright, sd_bright, upper);
    cv::meanStdDev(ratio8, mean_dark, sd_dark, ~upper);
    const double spread = std::sqrt(0.5 * (sd_bright[0] * sd_bright[0] + sd_dark[0] * sd_dark[0]));
    const bool separated = mean_bright[0] - mean_dark[0] > kMinSeparation * std::max(spread, 1.0);
    k_ratio = std::clamp(0.5 * (mean_bright[0] + mean_dark[0]) / 200.0, kMinRatio,
                         separated ? kMaxSeparatedRatio : kMaxRatio);
  } else {
    k_ratio = std::clamp(otsu / 200.0, kMinRatio, kMaxRatio);
  }

  // The threshold in 1/16 grey levels, widened to full width at low height
  // only; the vertical interpolation happens inside the compare, so no
  // full-size threshold image is written and read back.
  cv::Mat threshold_small;
  background.convertTo(threshold_small, CV_16U, 16 * k_ratio);
  const cv::Mat rows = widen(threshold_small, grey.cols);
  cv::Mat mask(grey.size(), CV_8UC1);
  const double scale = static_cast<double>(rows.rows) / grey.rows;
  cv::parallel_for_(cv::Range(0, grey.rows), [&](const cv::Range& range) {
    for (int y = range.start; y < range.end; ++y) {
      // Bilinear geometry of cv::resize: pixel centres, edges clamped.
      const double sy = std::max(0.0, (y + 0.5) * scale - 0.5);
      const int y0 = std::min(static_cast<int>(sy), rows.rows - 1);
      const int y1 = std::min(y0 + 1, rows.rows - 1);
      const int w1 = static_cast<int>(std::lround((sy - y0) * 16));
      compareRow(grey.ptr<uint8_t>(y), rows.ptr<uint16_t>(y0), rows.ptr<uint16_t>(y1), 16 - w1, w1,
                 mask.ptr<uint8_t>(y), grey.cols);
    }
  });
  return mask;
}
}  // namespace

int adaptiveWindow(cv::Size size, const BinarizeOptions& options) {
  return options.adaptive_window > 0 ? options.adaptive_window
                                     : std::min(size.width, size.height) / 6;
}

int windowForPart(double radius) {
  // The maximum filter reaches half a window from a pixel, and the blur after
  // it averages over another window: a margin of a quarter of the part keeps
  // the blurred estimate on the background level.
  return static_cast<int>(std::ceil(2.5 * std::max(radius, 0.0))) + 8;
}

cv::Mat binarize(const cv::Mat& grey, const BinarizeOptions& options) {
  CV_Assert(grey.type() == CV_8UC1);
  // Light parts on a dark background are dark parts on a light one, inverted.
  // (A fresh Mat: inverting into a header that shares `grey` would write
  // into the caller's frame.)
  cv::Mat input;
  if (options.polarity == Polarity::kLightOnDark) {
    cv::bitwise_not(grey, input);
  } else {
    input = grey;
  }
  cv::Mat mask;
  switch (options.method) {
    case ThresholdMethod::kFixed: {
      const int t = options.polarity == Polarity::kLightOnDark ? 255 - options.fixed_threshold
                                                               : options.fixed_threshold;
      cv::threshold(input, mask, t, 255, cv::THRESH_BINARY_INV);
      break;
    }
    case ThresholdMethod::kOtsu:
      cv::threshold(input, mask, 0, 255, cv::THRESH_BINARY_INV | cv::THRESH_OTSU);
      break;
    case ThresholdMethod::kAdaptive:
      mask = adaptive(input, adaptiveWindow(input.size(), options));
      break;
  }
  return mask;
}

}  // namespace picksight::vision
