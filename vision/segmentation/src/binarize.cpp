// Binarization. The adaptive method divides out the illumination: it
// estimates the lit background at low resolution (a maximum filter wider than
// any part erases the dark parts, a blur smooths it) and finds with Otsu the
// ratio part/background that separates the two populations. Where parts'
// edges run, their own steps then set the threshold (each step's middle),
// and the ratio decides only far from any edge: a part shaded lighter on one
// side, or lying on a darker blotch of a belt, is split at its own edge
// however little contrast it has. All heavy work is at 1/8 (the edges at
// 1/2) resolution; the full-resolution cost is one block mean and one
// compare against the threshold interpolated on the fly.
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
// How far (pixels, a Gaussian's sigma) an edge's level sets the threshold
// around it.
constexpr double kEdgeSpreadPx = 40;
// A step of this share of the scene's part/background contrast still sets
// the threshold: a part shaded to within ten levels of its belt has such
// edges on its light side.
constexpr double kMinStepShare = 0.3;
// A step whose dark side lies less than kMinStepShare of the contrast, and
// less than this share of the background, below the surface's typical level
// is a light mark on the surface, and does not vote (edgeVotes). Ten percent
// below the surface, a step's dark side is something on it: the soft outer
// edge of a shadow at 0.65 of the background on a belt at 0.78, 0.13 below
// it (short of kMinStepShare of the contrast, 0.17 of 0.57), still votes;
// without it the threshold left a thin layer of such shadows on their
// parts, too thin to be cut, and 3 of 60 parts beside a shadow were placed
// 1.6-1.9 px off.
constexpr double kMarkDepth = 0.1;
// Far from any edge, the threshold lies this share of the contrast below
// the middle of part and background.
constexpr double kOpenShare = 0.25;
// The weight of that open threshold, as a share of a typical voting cell's
// once spread: about three sigmas from the nearest edge, it decides.
constexpr double kPriorShare = 0.03;
// Surfaces whose level spreads (standard deviation, relative to the
// background estimate) by less than this share of the contrast are even:
// back-lit and plain scenes measure 0.05-0.065, a textured belt 0.1 and more,
// glossy parts or 30 levels of contrast 0.2-0.3. Only uneven ones are
// split at the parts' edges.
constexpr double kEvenSurface = 0.075;

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

// Immerkaer's noise response (the absolute response to a kernel that
// cancels any plane) of row `mid`, between rows `up` and `down`, added to
// `sum` and counted in `count` over the pixels whose Sobel magnitude (`gxs`,
// `gys`) is under `least` (not on an edge).
void addRowNoise(const uint8_t* up, const uint8_t* mid, const uint8_t* down, const int16_t* gxs,
                 const int16_t* gys, const std::vector<int>& least, int64_t* sum, int64_t* count) {
  const int width = static_cast<int>(least.size());
  for (int x = 1; x + 1 < width; ++x) {
    if (std::abs(gxs[x]) + std::abs(gys[x]) >= least[static_cast<size_t>(x)]) continue;
    const int residual = (up[x - 1] + up[x + 1] + down[x - 1] + down[x + 1]) -
                         2 * (up[x] + down[x] + mid[x - 1] + mid[x + 1]) + 4 * mid[x];
    *sum += std::abs(residual);
    ++*count;
  }
}

// The deviation of the noise from Immerkaer's residuals summed per cell
// row (added in row order: the same whatever the number of threads).
double noiseDeviation(const std::vector<int64_t>& residual_sums,
                      const std::vector<int64_t>& residual_counts) {
  int64_t residual_sum = 0;
  int64_t residual_count = 0;
  for (size_t j = 0; j < residual_sums.size(); ++j) {
    residual_sum += residual_sums[j];
    residual_count += residual_counts[j];
  }
  // The kernel's response to white noise of deviation s has mean absolute
  // value 6 s sqrt(2 / pi).
  return residual_count > 0 ? static_cast<double>(residual_sum) / residual_count /
                                  (6 * std::sqrt(2 / 3.14159265358979))
                            : 0;
}

// Where a part's edge runs, the threshold that splits it is the grey level
// halfway up its own step, whatever the light and the part's shading there.
// A single ratio to the background cannot follow a part shaded lighter on
// one side, or a surface blotched darker, once the contrast is a few tens of
// levels; the steps can. So the steps vote: every pixel on a sharp step of
// at least kMinStepShare of the scene's part/background contrast (`contrast`, a
// fraction of the background level) adds the level halfway up the step
// to its cell of the low-resolution grid (the size of
// `background`, `cell` pixels of `image` a cell). Blotches and wear change
// by a level or two a pixel and do not vote; noise steps are too small. The
// sums hold twice the middle levels.
// Steps whose middle lies above kMaxSeparatedRatio of the background (a
// glint on a part, a light mark on the surface) do not vote either. The sums
// are integers, each cell's written by one worker: the result does not
// depend on the number of threads. `surface` is the surface's typical level
// as a fraction of the background estimate (RatioSplit::surface).
void edgeVotes(const cv::Mat& image, int cell, const cv::Mat& background_f, double contrast,
               double surface, cv::Mat& level_sums, cv::Mat& weights, double* noise) {
  const int rows = background_f.rows;
  const int cols = background_f.cols;
  cv::Mat sums32(rows, cols, CV_32F, cv::Scalar(0));
  cv::Mat weights32(rows, cols, CV_32F, cv::Scalar(0));
  // Immerkaer's noise estimate (the mean absolute response to a kernel that
  // cancels any plane), over the pixels that are not on an edge: sums per
  // cell row, added in order.
  std::vector<int64_t> residual_sums(static_cast<size_t>(rows), 0);
  std::vector<int64_t> residual_counts(static_cast<size_t>(rows), 0);
  // The step is read this far either side of the pixel, across the edge:
  // beyond a blurred edge's ramp, within a thin part's width.
  constexpr float kReach = 2.5F;
  // Sobel's gradients (x and y), 8 for a ramp of one level a pixel.
  // Both in one pass over the frame: cv::spatialGradient is the two 3x3
  // cv::Sobel calls, with their default border.
  cv::Mat gradient_x;
  cv::Mat gradient_y;
  cv::spatialGradient(image, gradient_x, gradient_y, 3);
  // Each column's cell, looked up: a division a voting pixel (by a cell
  // size the compiler cannot know) cost as much as the rest of its vote.
  std::vector<int> column_cell(static_cast<size_t>(image.cols));
  for (int x = 0; x < image.cols; ++x) {
    column_cell[static_cast<size_t>(x)] = std::min(cols - 1, x / cell);
  }
  cv::parallel_for_(cv::Range(0, rows), [&](const cv::Range& range) {
    for (int j = range.start; j < range.end; ++j) {
      std::vector<int64_t> s(static_cast<size_t>(cols), 0);
      std::vector<int64_t> w(static_cast<size_t>(cols), 0);
      int64_t residual_sum = 0;
      int64_t residual_count = 0;
      const int y_end = j == rows - 1 ? image.rows - 1 : std::min(image.rows - 1, (j + 1) * cell);
      const int width = image.cols;
      const float* back = background_f.ptr<float>(j);
      // The least Sobel magnitude (|gx| + |gy|) of a pixel that may vote,
      // per column: Sobel gives 8 for a ramp of one level a pixel, so a step
      // of `step` over about two pixels gives 4 * step; a quarter of it.
      std::vector<int> least(static_cast<size_t>(width));
      std::vector<double> steps(static_cast<size_t>(width));
      for (int x = 0; x < width; ++x) {
        const double step = contrast * back[column_cell[static_cast<size_t>(x)]];
        steps[static_cast<size_t>(x)] = step;
        least[static_cast<size_t>(x)] = std::max(1, static_cast<int>(std::ceil(step)));
      }
      for (int y = std::max(1, j * cell); y < y_end; ++y) {
        const uint8_t* up = image.ptr<uint8_t>(y - 1);
        const uint8_t* mid = image.ptr<uint8_t>(y);
        const uint8_t* down = image.ptr<uint8_t>(y + 1);
        const int16_t* gxs = gradient_x.ptr<int16_t>(y);
        const int16_t* gys = gradient_y.ptr<int16_t>(y);
        // The noise, off the edges, from every fourth row: plenty of pixels.
        if (y % 4 == 0) {
          addRowNoise(up, mid, down, gxs, gys, least, &residual_sum, &residual_count);
        }
        for (int x = 1; x + 1 < width; ++x) {
          const int gx = gxs[x];
          const int gy = gys[x];
          if (std::abs(gx) + std::abs(gy) < least[static_cast<size_t>(x)]) continue;
          const int i = column_cell[static_cast<size_t>(x)];
          const double step = steps[static_cast<size_t>(x)];
          const float reach =
              kReach / std::sqrt(static_cast<float>(gx) * gx + static_cast<float>(gy) * gy);
          const int dx = cvRound(reach * gx);
          const int dy = cvRound(reach * gy);
          const int xl = std::clamp(x - dx, 0, width - 1);
          const int yl = std::clamp(y - dy, 0, image.rows - 1);
          const int xh = std::clamp(x + dx, 0, width - 1);
          const int yh = std::clamp(y + dy, 0, image.rows - 1);
          const int lo = image.at<uint8_t>(yl, xl);
          const int hi = image.at<uint8_t>(yh, xh);
          // The step's middle, read from its two sides: the same wherever on
          // the ramp this pixel lies.
          const int middle = lo + hi;  // twice the middle level
          if (hi - lo < kMinStepShare * step || middle > 2 * kMaxSeparatedRatio * back[i]) continue;
          // A light mark on the surface (the mortar between paving bricks,
          // a light fleck of gravel, a scratch) steps up from the surface's
          // own level: its dark side is the surface. Its middle lies above
          // the surface's level, and voting there split the surface itself
          // (photographed brick at 30 grey levels: every brick a region).
          // A part's edge, even its light side's, steps down below it, and
          // so does a shadow's (kMarkDepth).
          if (surface * back[i] - lo < std::min(kMinStepShare * step, kMarkDepth * back[i]))
            continue;
          // A surface beside a part stays light beyond the edge; the
          // stripes of wood grain or a ribbed belt fall dark again a few
          // pixels on, and their steps do not vote.
          const int xf = std::clamp(x + 2 * dx, 0, width - 1);
          const int yf = std::clamp(y + 2 * dy, 0, image.rows - 1);
          if (4 * (image.at<uint8_t>(yf, xf) - lo) < 3 * (hi - lo)) continue;
          // One vote a pixel, however strong the step: a part's light
          // side, ten levels from its belt, must not be outvoted by its
          // dark side's edges a part's width away.
          s[static_cast<size_t>(i)] += middle;
          w[static_cast<size_t>(i)] += 1;
        }
      }
      residual_sums[static_cast<size_t>(j)] = residual_sum;
      residual_counts[static_cast<size_t>(j)] = residual_count;
      float* so = sums32.ptr<float>(j);
      float* wo = weights32.ptr<float>(j);
      for (int i = 0; i < cols; ++i) {
        so[i] = static_cast<float>(s[static_cast<size_t>(i)]);
        wo[i] = static_cast<float>(w[static_cast<size_t>(i)]);
      }
    }
  });
  level_sums = sums32;
  weights = weights32;
  *noise = noiseDeviation(residual_sums, residual_counts);
}

struct GuidedThreshold {
  cv::Mat level;     // CV_32F, grey levels, the size of the background estimate
  double noise = 0;  // estimated deviation of a full-resolution pixel's noise and grain
};

// The threshold at low resolution (CV_32F, grey levels): the edges' votes
// spread over about kEdgeSpreadPx (less where the illumination window, `k`
// cells, is narrow), with `fallback` as a weak prior, so that far from any
// edge (open surface, the middle of a large part) it decides, and near edges
// their own levels do. Never above kMaxSeparatedRatio of the background: the
// surface's own blotches stay surface. Also the noise (edgeVotes).
GuidedThreshold edgeGuidedThreshold(const cv::Mat& grey, int reduce, int k,
                                    const cv::Mat& background_f, double contrast, double surface,
                                    const cv::Mat& fallback) {
  cv::Mat image;
  int cell = reduce;
  double noise_scale = 1;
  // Half resolution where a cell holds whole half-size pixels: a quarter of
  // the work, and steps of a sharp edge still a pixel or two wide.
  if (reduce % 2 == 0 && grey.cols >= 4 && grey.rows >= 4) {
    cv::resize(grey, image, cv::Size(grey.cols / 2, grey.rows / 2), 0, 0, cv::INTER_AREA);
    cell = reduce / 2;
    // Averaging four pixels halves independent noise.
    noise_scale = 2;
  } else {
    image = grey;
  }
  cv::Mat sums;
  cv::Mat weights;
  GuidedThreshold out;
  edgeVotes(image, cell, background_f, contrast, surface, sums, weights, &out.noise);
  out.noise *= noise_scale;
  std::vector<cv::Point> voting;
  for (int j = 0; j < weights.rows; ++j) {
    const float* w = weights.ptr<float>(j);
    for (int i = 0; i < weights.cols; ++i) {
      if (w[i] > 0) voting.emplace_back(i, j);
    }
  }
  if (voting.empty()) {
    out.level = fallback;
    return out;
  }
  // Spread over about 40 pixels (a quarter of the window when that is
  // smaller): a part's shading and a belt's blotches change over tens of
  // pixels, and the wide window that keeps a large part whole would average
  // the light side of a part with its dark side.
  const double sigma = std::max(1.0, std::min(k / 4.0, kEdgeSpreadPx / reduce));
  cv::GaussianBlur(sums, sums, cv::Size(0, 0), sigma);
  cv::GaussianBlur(weights, weights, cv::Size(0, 0), sigma);
  // The prior (kPriorShare) against what a typical voting cell holds once
  // spread.
  std::vector<double> held;
  held.reserve(voting.size());
  for (const cv::Point& p : voting) held.push_back(weights.at<float>(p));
  const auto middle = held.begin() + static_cast<std::ptrdiff_t>(held.size() / 2);
  std::nth_element(held.begin(), middle, held.end());
  const double prior = kPriorShare * *middle;
  const cv::Mat blended = (0.5 * sums + prior * fallback) / (weights + prior);
  out.level = cv::min(blended, background_f * kMaxSeparatedRatio);
  return out;
}

// How the ratio of the image to its background splits (see adaptive).
struct RatioSplit {
  double k_ratio = kMaxRatio;  // the ratio parts lie below
  // Part/background, a fraction of the background level, where the edges
  // set the threshold; 0 where the ratio alone does.
  double contrast = 0;
  // The surface's typical level, a fraction of the background level: the
  // background estimate is the local maximum, the surface's lightest marks.
  double surface = 1;
};

// The split where the parts' level is known (BinarizeOptions::part_level)
// and the frame's is not two populations: the surface is the frame's median
// ratio (most of such a frame is surface), the parts lie at `part_level` of
// it, and the split is halfway.
RatioSplit splitAtPartLevel(const cv::Mat& ratio8, double part_level) {
  std::vector<uint8_t> levels(ratio8.begin<uint8_t>(), ratio8.end<uint8_t>());
  const auto mid = levels.begin() + static_cast<std::ptrdiff_t>(levels.size() / 2);
  std::nth_element(levels.begin(), mid, levels.end());
  const double surface = *mid / 200.0;
  RatioSplit split;
  split.k_ratio = std::clamp(0.5 * (1 + part_level) * surface, kMinRatio, kMaxSeparatedRatio);
  split.contrast = (1 - part_level) * surface;
  split.surface = surface;
  return split;
}

// The split of the ratio image (200 = the background's level) of `small_f`
// to `background_f`, both at low resolution (`part_level`: see
// BinarizeOptions).
RatioSplit splitRatio(const cv::Mat& small_f, const cv::Mat& background_f, double part_level) {
  cv::Mat ratio;
  cv::divide(small_f, cv::max(background_f, 1.0f), ratio, 200.0);
  cv::Mat ratio8;
  ratio.convertTo(ratio8, CV_8U);
  cv::Mat upper;
  const double otsu = cv::threshold(ratio8, upper, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
  // Otsu's level is the first of a flat optimum: with two clean populations it
  // sits on the edge of the darker one. Split halfway between the two class
  // means instead, where noise on either side is least likely to cross.
  RatioSplit split;
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
    // Not two populations: a frame of surface with a part or two on a
    // grainy surface (gravel: Otsu split the stones' own shades, the
    // contrast came out a third of the part's, and every stone's edge
    // voted: the part's outline took in the crevices beside it).
    if (!separated && part_level > 0 && part_level < 1) return splitAtPartLevel(ratio8, part_level);
    split.k_ratio = std::clamp(0.5 * (mean_bright[0] + mean_dark[0]) / 200.0, kMinRatio,
                               separated ? kMaxSeparatedRatio : kMaxRatio);
    // An even surface (its spread a small share of the contrast: a back
    // light, a plain tray) is split exactly by the ratio, at no further cost.
    if (sd_bright[0] > kEvenSurface * (mean_bright[0] - mean_dark[0])) {
      split.contrast = (mean_bright[0] - mean_dark[0]) / 200.0;
      split.surface = mean_bright[0] / 200.0;
    }
  } else {
    split.k_ratio = std::clamp(otsu / 200.0, kMinRatio, kMaxRatio);
  }
  return split;
}

cv::Mat adaptive(const cv::Mat& grey, int window, double part_level) {
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

  cv::Mat small_f;
  cv::Mat background_f;
  small.convertTo(small_f, CV_32F);
  background.convertTo(background_f, CV_32F);
  const RatioSplit split = splitRatio(small_f, background_f, part_level);
  const double k_ratio = split.k_ratio;
  const double contrast = split.contrast;

  // The threshold in 1/16 grey levels, widened to full width at low height
  // only; the vertical interpolation happens inside the compare, so no
  // full-size threshold image is written and read back.
  cv::Mat threshold_small;
  bool smooth = false;
  if (contrast > 0) {
    // Far from every edge the surface is open, or the middle of a part
    // wider than the edges reach: the ratio splits those, but a quarter of
    // the contrast lower than halfway, since a belt's blotches lie there
    // and a part's middle lies far below it.
    const cv::Mat global_threshold = background_f * (k_ratio - kOpenShare * contrast);
    const GuidedThreshold guided = edgeGuidedThreshold(grey, reduce, k, background_f, contrast,
                                                       split.surface, global_threshold);
    guided.level.convertTo(threshold_small, CV_16U, 16);
    // Where half the contrast is within six deviations of the noise, single
    // pixels cross the threshold on both sides of the weaker edges (a part's
    // light side, a third of the contrast from its belt) and a low-contrast
    // part breaks into specks: compare the 3x3 mean instead, a third of the
    // noise. Edges stay where they were (a symmetric mean does not move a
    // step's middle); the grey levels read for coverage are the frame's own.
    // Only then: the mean also closes a small blurred hole, or the one-pixel
    // gap between two parts that touch.
    const double margin = 0.5 * contrast * cv::mean(background_f)[0];
    smooth = 6 * guided.noise > margin;
  } else {
    background.convertTo(threshold_small, CV_16U, 16 * k_ratio);
  }
  const cv::Mat rows = widen(threshold_small, grey.cols);
  cv::Mat mask(grey.size(), CV_8UC1);
  const double scale = static_cast<double>(rows.rows) / grey.rows;
  cv::parallel_for_(cv::Range(0, grey.rows), [&](const cv::Range& range) {
    std::vector<uint16_t> sums(smooth ? static_cast<size_t>(grey.cols) + 2 : 0);
    std::vector<uint8_t> mean(smooth ? static_cast<size_t>(grey.cols) : 0);
    for (int y = range.start; y < range.end; ++y) {
      // Bilinear geometry of cv::resize: pixel centres, edges clamped.
      const double sy = std::max(0.0, (y + 0.5) * scale - 0.5);
      const int y0 = std::min(static_cast<int>(sy), rows.rows - 1);
      const int y1 = std::min(y0 + 1, rows.rows - 1);
      const int w1 = static_cast<int>(std::lround((sy - y0) * 16));
      const uint8_t* compared = grey.ptr<uint8_t>(y);
      if (smooth) {
        meanRow3x3(grey, y, sums.data(), mean.data());
        compared = mean.data();
      }
      compareRow(compared, rows.ptr<uint16_t>(y0), rows.ptr<uint16_t>(y1), 16 - w1, w1,
                 mask.ptr<uint8_t>(y), grey.cols);
    }
  });
  return mask;
}
}  // namespace

// Made row by row where the rows are compared, so the smoothed frame is
// neither written nor read back (cv::blur on a whole full-HD frame is one
// thread's millisecond).
void meanRow3x3(const cv::Mat& grey, int y, uint16_t* sums, uint8_t* out) {
  const uint8_t* up = grey.ptr<uint8_t>(std::max(y - 1, 0));
  const uint8_t* mid = grey.ptr<uint8_t>(y);
  const uint8_t* down = grey.ptr<uint8_t>(std::min(y + 1, grey.rows - 1));
  const int n = grey.cols;
  uint16_t* s = sums + 1;
  int x = 0;
#if CV_SIMD128
  for (; x + 16 <= n; x += 16) {
    cv::v_uint16x8 u0;
    cv::v_uint16x8 u1;
    cv::v_uint16x8 m0;
    cv::v_uint16x8 m1;
    cv::v_uint16x8 d0;
    cv::v_uint16x8 d1;
    cv::v_expand(cv::v_load(up + x), u0, u1);
    cv::v_expand(cv::v_load(mid + x), m0, m1);
    cv::v_expand(cv::v_load(down + x), d0, d1);
    cv::v_store(s + x, u0 + m0 + d0);
    cv::v_store(s + x + 8, u1 + m1 + d1);
  }
#endif
  for (; x < n; ++x) s[x] = static_cast<uint16_t>(up[x] + mid[x] + down[x]);
  s[-1] = s[0];
  s[n] = s[n - 1];
  // Nine levels sum to at most 2295; (t + 4) / 9 is t / 9 rounded (a ninth
  // is never a half), and (t + 4) * 7282 >> 16 is that quotient exactly:
  // 7282 / 2^16 exceeds a ninth by 3.4e-6, which over t + 4 < 2300 adds
  // under 0.008 to a fraction of at most 8/9.
  x = 0;
#if CV_SIMD128
  const cv::v_uint16x8 four = cv::v_setall_u16(4);
  const cv::v_uint16x8 ninth = cv::v_setall_u16(7282);
  for (; x + 16 <= n; x += 16) {
    const cv::v_uint16x8 t0 = cv::v_load(s + x - 1) + cv::v_load(s + x) + cv::v_load(s + x + 1);
    const cv::v_uint16x8 t1 = cv::v_load(s + x + 7) + cv::v_load(s + x + 8) + cv::v_load(s + x + 9);
    cv::v_store(out + x,
                cv::v_pack(cv::v_mul_hi(t0 + four, ninth), cv::v_mul_hi(t1 + four, ninth)));
  }
#endif
  for (; x < n; ++x) out[x] = static_cast<uint8_t>((s[x - 1] + s[x] + s[x + 1] + 4) / 9);
}

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
      mask = adaptive(input, adaptiveWindow(input.size(), options), options.part_level);
      break;
  }
  return mask;
}

}  // namespace picksight::vision
