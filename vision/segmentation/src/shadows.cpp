// Cast shadows cut off dark parts (see shadows.hpp): per region, on its box,
// the thick layer of levels between the part's and the surface's.
#include "picksight/vision/segmentation/shadows.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

#include "fill_contour.hpp"
#include "picksight/vision/segmentation/disc_morphology.hpp"
#include "picksight/vision/segmentation/row_runs.hpp"

namespace picksight::vision {
namespace {
// Pixels lighter than the part by this share of the contrast are the edge's
// blur or a shadow; the blur between 25 % and the threshold (near 50 %) is
// under a pixel thick for an edge blurred by 1.5 px.
constexpr double kLighterShare = 0.25;
// The part's own level is read this deep inside it, and a shadow's core
// lies deeper in the mask than this (pixels): past the blur of any edge at
// kLighterShare, so that a layer from 4 px thick (the shadow of a part a few
// millimetres high under a lamp at 45 degrees) shows.
constexpr int kCoreDepth = 2;
// A shadow's layer inside the mask is at least this many pixels thick on
// average (its pixels over its length on the outline), an edge's blur
// about one. (At 2, the front-light benchmark's shadowed parts, separated,
// were placed 0.12 px off instead of 0.08: thin stretches of shadow along
// the parts' flanks stayed on them.)
constexpr double kMinLayerThickness = 1.5;
// Where a layer meets the rest of the part, the levels are read this far
// either side (pixels), and must differ by this share of the levels
// between the layer and the part: a step (a shadow, beside the part's own
// edge) and not a slope (the part's lit side).
constexpr int kStepReadPx = 3;
constexpr double kMinStepShare = 0.4;
// ... and the layer's pixels deeper in the mask than the edge's blur
// (kCoreDepth) alone, where there are kMinCorePixels of them, by this
// share: the layer's outermost pixels are the edge's blur towards the
// surface, lighter than either side, and with them a part's lit end steps
// as a shadow does. A part at 30 grey levels of contrast, shaded by 15 %
// of its level across its face, taught from a frame with a third of the
// front-light benchmark's noise (a quieter camera): its lit lobe's tip,
// 9 levels over the rest of the part, stepped 0.54-0.66 of that with its
// rim, 0.16-0.20 without, and was cut as a shadow (938 pixels; the model
// taught 1.8 px off). Shadows beside the benchmark's parts (both type
// sets, 3 scenes of each arrangement, 215-224 layers a lens) step 0.51 and
// more without their rim under a sharp lens, 0.41 blurred by 1.5 px, 0.32
// by 2.5.
constexpr double kMinCoreStepShare = 0.25;
// Fewer pixels than these are noise, or a corner of the blur.
constexpr int kMinShadowPixels = 30;
constexpr int kMinCorePixels = 12;
// The shadow's level lies this many times the part's own spread (its noise,
// texture and shading) above the part's level: a part shaded across its
// face has no second level, only a wider first one.
constexpr double kSpreadsApart = 4;
// And below the surface's by this share of the contrast: a layer at the
// surface's level is the surface.
constexpr double kBelowSurface = 0.15;
// Parts less contrasted than this (grey levels) are not searched for
// shadows: a shadow would be within the noise.
constexpr double kMinContrast = 20;
// The surface is read in a ring this far out of the region (pixels), past
// the edge's blur.
constexpr int kRingInner = 3;
constexpr int kRingOuter = 6;
// The part is thresholded against its shadow within this distance of the
// shadow (pixels): the shadow's own edge blur and the part's.
constexpr int kCutReach = 3;
// The level outside the part is read this far past the ring it is read in.
constexpr int kZoneReach = 2;
// The level just outside the part is read in a ring this far out (pixels),
// averaged with Gaussian weights of this sigma; where they sum to less than
// kMinOutsideWeight no ring pixel is near. As near as the edge's blur allows:
// a shadow lightens away from the part (along a flank, its penumbra starts
// at the edge), and a level read further out is lighter than the shadow
// under the part's edge, which then reads as part. Read 2-5 px out, parts
// beside a shadow were 1 % too large and 0.17-0.28 px off towards it; 1-2 px
// out, 0.02-0.07 px (tests/vision/front_light_regions_test.cpp).
constexpr int kNearOut = 1;
constexpr int kFarOut = 2;
constexpr double kOutsideSigma = 1.5;
constexpr float kMinOutsideWeight = 0.02f;
// A ring pixel is in a shadow when darker than the surface by more than
// this many times the surface's spread (its texture) and kBelowSurface of
// the contrast.
constexpr double kTextureSpreads = 3;
// Fewer points of the outline than this (or a twentieth of them) showing
// a shadow's levels beside them are noise and texture.
constexpr size_t kMinOddSides = 3;
// Out of focus, a part's edge darkens the surface beside it further out:
// the rings above are read past kClearBlurs sigmas of the lens's blur,
// where the edge is within 4 % of the surface's level (at the distances
// above when the lens is sharp, sigma under 1.1 px). Read 1-2 px out of an
// edge blurred by 2 px, the level beside every part was a fifth of the
// contrast darker than the surface, and every edge pixel lighter than
// halfway to it was cut off as a thin shadow: the front-light benchmark's
// parts, no shadow cast, were placed 2 px off on a glossy belt, 0.13 px on
// a textured one. A thin shadow is then read at the lighter level further
// out, and partly left on the part: so blurred, it is told from the edge's
// own blur no better.
constexpr double kClearBlurs = 1.8;
// The blur is read across every kBlurStep-th outline point, kBlurReachPx
// either way, where the levels step by kBlurStepShare of the highest steps
// (the lit surface's: not a shadow's or the noise's).
constexpr int kBlurStep = 4;
constexpr int kBlurReachPx = 5;
constexpr double kBlurStepShare = 0.5;
// The blur edgeBlur reads on a sharp edge (the pixels' area, bilinear reads,
// a slope taken over two pixels), taken out in quadrature to leave the
// lens's: the benchmark's parts blurred by 0.7, 1.0, 1.5, 2.0 and 2.5 px
// read about 1.26, 1.47, 1.87, 2.2 and 2.47. Reads above kMaxBlurPx are
// taken as that (a 5 px reach sees no more).
constexpr double kSamplingBlurPx = 1.05;
constexpr double kMaxBlurPx = 3.0;

// The distances the levels beside a part are read at, for a lens's blur.
struct Reaches {
  int ring_inner = kRingInner;  // the surface's ring, to twice this
  int near_out = kNearOut;      // the level just outside, between these
  int far_out = kFarOut;
  double outside_sigma = kOutsideSigma;
};

Reaches reachesFor(double blur_px) {
  const int clear = static_cast<int>(std::ceil(kClearBlurs * blur_px));
  Reaches r;
  r.far_out = std::max(kFarOut, clear);
  r.near_out = r.far_out - (kFarOut - kNearOut);
  r.ring_inner = std::max(kRingInner, clear + 1);
  r.outside_sigma = kOutsideSigma * r.far_out / kFarOut;
  return r;
}

using Histogram = std::array<int, 256>;

// The level below which `share` of the histogram's `count` values lie.
double quantileOf(const Histogram& h, int count, double share) {
  int below = 0;
  for (size_t v = 0; v < h.size(); ++v) {
    below += h[v];
    if (below >= share * count) return static_cast<double>(v);
  }
  return 255.0;
}

// A level and its spread (a standard deviation's worth).
struct Level {
  double level = 0;
  double spread = 0;
  bool shadowed = false;  // litSurfaceLevel: read above a shadow's levels
};

// The median of the histogram's values and their spread (the median
// absolute deviation, scaled to a standard deviation).
Level medianLevel(const Histogram& h, int count) {
  Level l;
  l.level = quantileOf(h, count, 0.5);
  Histogram deviations{};
  for (size_t v = 0; v < h.size(); ++v) {
    deviations[static_cast<size_t>(std::abs(static_cast<double>(v) - l.level))] += h[v];
  }
  l.spread = 1.4826 * quantileOf(deviations, count, 0.5);
  return l;
}

// The lit surface beside a part, from the levels read round it. A cast
// shadow darkens them on one side only; along most of the outline (a
// triangle two of whose sides face away from the lamp, a shadow a few
// pixels wide at 3 px out), their median is the shadow's and their spread
// the step between shadow and surface: read so, a triangle beside its
// shadow kept it (its region 4 % too large, 1.4-1.8 px off, under the lamp
// from 2 or 3 of 8 directions; tests/vision/front_light_regions_test.cpp).
// Such levels have their median in a lower mass well apart from the upper
// one: the upper quartile lies more than kShadowedSkew times as far above
// the median as the 90th percentile above it (a symmetric texture's 1.1, a
// part's lit surface under the benchmark's light fall-off 1.2-1.5; the
// triangle's 3-5), and more than kShadowStepShare of the contrast to
// `part` and kTextureSpreads of `noise` (the noise along the outline,
// noiseAlong). The surface is then the
// upper quartile, its spread that of the upper tail (for a normal spread,
// 0.607 of it between the 75th and 90th percentiles).
constexpr double kShadowedSkew = 2.5;
constexpr double kMinSkewSpan = 2.0;  // grey levels: quantisation, not skew
// The step from a shadow's levels up to the surface's is at least this
// share of the contrast (and three of the noise's spreads along the
// outline). A belt's blotches and a glossy part's rim skew
// the levels beside a part by less. Six shapes that cast no shadow, 30
// noise seeds, two turns: with no bound, 10 of 1440 images (four
// front-light conditions) were cut 0.4-0.8 % and moved up to 0.13 px, which
// they were not before; with 15 % of the contrast, one of 2160 (six
// conditions: a glossy part, 0.8 %, 0.08 px); with 25 %, none (the
// triangle's step is 38 % of its contrast). With no bound the front-light
// benchmark lost one overlapping part of 125 at 30 grey levels.
constexpr double kShadowStepShare = 0.25;
Level litSurfaceLevel(const Histogram& h, int count, double part, double noise) {
  const Level whole = medianLevel(h, count);
  const double min_step =
      std::max(kShadowStepShare * (whole.level - part), kTextureSpreads * noise);
  const double upper = quantileOf(h, count, 0.75);
  const double top = quantileOf(h, count, 0.9);
  if (upper - whole.level >
      std::max(min_step, kShadowedSkew * std::max(top - upper, kMinSkewSpan))) {
    return {upper, (top - upper) / 0.607, true};
  }
  return whole;
}

// The spread of the histogram's values above `level` (their median
// distance above it, scaled to a standard deviation); -1 when none.
double spreadAbove(const Histogram& h, double level) {
  const auto from = static_cast<size_t>(std::clamp(std::ceil(level), 0.0, 255.0));
  int above = 0;
  for (size_t v = from; v < h.size(); ++v) above += h[v];
  int seen = 0;
  for (size_t v = from; v < h.size(); ++v) {
    seen += h[v];
    if (2 * seen >= above && above > 0) return 1.4826 * (static_cast<double>(v) - level);
  }
  return -1;
}

// The histogram of `grey` where `where` is set, and its count.
int histogramOf(const cv::Mat& grey, const cv::Mat& where, Histogram* histogram) {
  // Four counts per level, without a branch per pixel (a mask's pixels set
  // and unset alternate unpredictably at its edge), summed after: this
  // count took 95 M of the 1.2 G instructions of the shadow cuts of a
  // front-lit frame (callgrind), 76 M so.
  std::array<Histogram, 4> partial{};
  for (int y = 0; y < grey.rows; ++y) {
    const uint8_t* g = grey.ptr<uint8_t>(y);
    const uint8_t* w = where.ptr<uint8_t>(y);
    int x = 0;
#if CV_SIMD128
    // Sixteen pixels none of which is counted are passed over at once: a
    // ring or a shadow's layer leaves most of its box empty.
    for (; x + 16 <= grey.cols; x += 16) {
      if (!cv::v_check_any(cv::v_load(w + x) != cv::v_setzero_u8())) continue;
      for (int i = x; i < x + 16; i += 4) {
        partial[0][g[i]] += w[i] != 0;
        partial[1][g[i + 1]] += w[i + 1] != 0;
        partial[2][g[i + 2]] += w[i + 2] != 0;
        partial[3][g[i + 3]] += w[i + 3] != 0;
      }
    }
#endif
    for (; x + 4 <= grey.cols; x += 4) {
      partial[0][g[x]] += w[x] != 0;
      partial[1][g[x + 1]] += w[x + 1] != 0;
      partial[2][g[x + 2]] += w[x + 2] != 0;
      partial[3][g[x + 3]] += w[x + 3] != 0;
    }
    for (; x < grey.cols; ++x) partial[0][g[x]] += w[x] != 0;
  }
  int count = 0;
  for (size_t v = 0; v < histogram->size(); ++v) {
    (*histogram)[v] = partial[0][v] + partial[1][v] + partial[2][v] + partial[3][v];
    count += (*histogram)[v];
  }
  return count;
}

// The median of the levels of `grey` where `where` is set, and their spread
// (the median absolute deviation, scaled to a standard deviation); false
// when fewer than `min_count` pixels.
bool levelsOf(const cv::Mat& grey, const cv::Mat& where, int min_count, double* median,
              double* spread = nullptr) {
  Histogram h{};
  const int count = histogramOf(grey, where, &h);
  if (count < min_count) return false;
  const Level l = medianLevel(h, count);
  *median = l.level;
  if (spread != nullptr) *spread = l.spread;
  return true;
}

#if CV_SIMD128
// Sixteen bytes as four quads of 32-bit lanes: loaded whole
// (v_load_expand_q reads four bytes as an int, misaligned, which UBSan
// refuses) and widened.
std::array<cv::v_uint32x4, 4> widened(const uint8_t* sixteen) {
  cv::v_uint16x8 low;
  cv::v_uint16x8 high;
  cv::v_expand(cv::v_load(sixteen), low, high);
  std::array<cv::v_uint32x4, 4> lanes;
  cv::v_expand(low, lanes[0], lanes[1]);
  cv::v_expand(high, lanes[2], lanes[3]);
  return lanes;
}
#endif

// What one region's shadow changes, over its box.
struct RegionCut {
  double blur_px = 0;  // the lens's blur at the region's edge (edgeBlur)
  cv::Rect box;
  cv::Mat removed;  // the region's pixels that are its shadow
  cv::Mat zone;     // where the level outside the part is the shadow's
};

// The levels of a region's box it is read against: the part's (its median
// deep inside, and its spread), the surface's in a ring past the edge's
// blur (and the ring's spread: the surface's texture and noise).
struct Levels {
  double part = 0;
  double part_spread = 0;
  double surface = 0;
  double surface_spread = 0;
  double contrast() const { return surface - part; }
};

// The thick layer of a shadow inside the mask (see shadows.hpp): pixels
// lighter than the part by kLighterShare of the contrast around a core
// deeper in the mask than any edge's blur reaches at that level (3 px in,
// an edge blurred by 2.5 px is 2 % of the way to the surface), on the
// outline, at a level of their own. 255 there; empty when none.
// `interior` is `own` eroded by kCoreDepth.
cv::Mat thickLayer(const cv::Mat& g, const cv::Mat& own, const cv::Mat& interior, const Levels& l) {
  cv::Mat lighter;
  cv::compare(g, l.part + kLighterShare * l.contrast(), lighter, cv::CMP_GT);
  cv::bitwise_and(lighter, own, lighter);
  if (cv::countNonZero(lighter) < kMinShadowPixels) return {};
  cv::Mat core;
  cv::bitwise_and(interior, lighter, core);
  if (cv::countNonZero(core) < kMinCorePixels) return {};
  // The layers lie within kCoreDepth + 1 of the core, and what follows
  // reads them and kStepReadPx round them: all of it is done on the
  // rectangle that holds those (a shadow lies along a side or two of the
  // part), each result the same as over the box.
  // Views of the box's images read their neighbours past the rectangle as
  // the whole image would; `rest` and the dilations of the layers, made
  // here, need none (the layers are a margin inside the rectangle).
  const int margin = kCoreDepth + 1 + kStepReadPx + 1;
  const cv::Rect r =
      (cv::boundingRect(core) + cv::Size(2 * margin, 2 * margin) - cv::Point(margin, margin)) &
      cv::Rect(0, 0, own.cols, own.rows);
  cv::Mat shadow = cv::Mat::zeros(own.size(), CV_8UC1);
  cv::Mat layers = shadow(r);
  dilateMask(core(r), layers, kCoreDepth + 1);
  cv::bitwise_and(layers, lighter(r), layers);
  // Only layers on the outline: a lighter patch inside the part (a mark, a
  // highlight) is the part's.
  cv::Mat outline;
  cv::erode(own(r), outline, cv::Mat());
  cv::bitwise_xor(own(r), outline, outline);
  cv::Mat labels;
  const int n = cv::connectedComponents(layers, labels, 8, CV_32S);
  // Per layer: its pixels, and those on the outline (label 0, the rest of
  // the box, is counted on the outline too and not read). Read over the
  // layers' and the outline's pixels alone: a loop over every label of the
  // rectangle, and another to write the kept layers back, were a fifth of
  // the thick layer's search.
  std::vector<int> pixels(static_cast<size_t>(n), 0);
  std::vector<int> on_outline(static_cast<size_t>(n), 0);
  forEachSetPixel(layers,
                  [&](int x, int y) { ++pixels[static_cast<size_t>(labels.at<int>(y, x))]; });
  forEachSetPixel(outline,
                  [&](int x, int y) { ++on_outline[static_cast<size_t>(labels.at<int>(y, x))]; });
  // A shadow lies along the outline, a few pixels thick. Not a shadow:
  // specks of the edge's blur along the outline (each fewer than
  // kMinShadowPixels, though many of them reach it together) or a fringe of
  // it (thinner than kMinLayerThickness: the blurred tips of a part's arms
  // on its lit side). Counted as one, they took 2 % of a part shaded within
  // a few levels of its belt and moved it 1.1 px; of a glossy part, beside
  // its glints, 1.6 px.
  std::vector<uint8_t> kept(static_cast<size_t>(n), 0);  // 255: a shadow's layer
  for (size_t k = 1; k < kept.size(); ++k) {
    kept[k] = on_outline[k] > 0 && pixels[k] >= kMinShadowPixels &&
                      pixels[k] >= kMinLayerThickness * on_outline[k]
                  ? 255
                  : 0;
  }
  // Unset pixels are label 0, never kept.
  forEachSetPixel(layers, [&](int x, int y) {
    layers.at<uint8_t>(y, x) = kept[static_cast<size_t>(labels.at<int>(y, x))];
  });
  double level = 0;
  if (!levelsOf(g(r), layers, kMinShadowPixels, &level)) return {};
  if (level - l.part < kSpreadsApart * l.part_spread ||
      l.surface - level < kBelowSurface * l.contrast()) {
    return {};
  }
  // A shadow meets the part at the part's own edge, a step within the
  // edge's blur; the lit side of a part shaded across its face (a light
  // from one side) meets the rest of it at a slope. Read a few pixels either
  // side of where they meet, a shadow's two sides differ by most of the
  // levels between the part and the layer, a lit side's by a small share.
  cv::Mat rest;
  cv::bitwise_and(own(r), ~layers, rest);
  cv::Mat near;
  dilateMask(rest, near, kStepReadPx);
  cv::Mat layer_side;
  cv::bitwise_and(near, layers, layer_side);
  dilateMask(layers, near, kStepReadPx);
  cv::Mat part_side;
  cv::bitwise_and(near, rest, part_side);
  if (cv::countNonZero(layer_side) < kMinCorePixels || cv::countNonZero(part_side) < kMinCorePixels)
    return {};
  const double part_side_level = cv::mean(g(r), part_side)[0];
  const double step = cv::mean(g(r), layer_side)[0] - part_side_level;
  if (step < kMinStepShare * (level - l.part)) return {};
  cv::Mat deep_side;
  cv::bitwise_and(layer_side, interior(r), deep_side);
  if (cv::countNonZero(deep_side) >= kMinCorePixels &&
      cv::mean(g(r), deep_side)[0] - part_side_level < kMinCoreStepShare * (level - l.part)) {
    return {};
  }
  return shadow;
}

// The noise of samples read in turn along an outline (a standard
// deviation): from the differences of neighbours, which a shadow changes
// only where it starts and ends, while it may take half of the samples
// and would widen their spread about any one level until it hid itself.
double noiseAlong(const std::vector<float>& values) {
  if (values.size() < 2) return 0;
  std::vector<float> steps(values.size() - 1);
  for (size_t k = 1; k < values.size(); ++k) steps[k - 1] = std::abs(values[k] - values[k - 1]);
  // The median absolute difference of two independent readings is
  // 0.6745 * sqrt(2) of their standard deviation.
  return medianOf(steps) / (0.6745 * std::sqrt(2.0));
}

// Whether the levels a few pixels in and out of the region's outline
// (sideSamples) leave room for a shadow: some inside lighter than the part
// by kLighterShare of the contrast, or outside darker than the surface by
// kBelowSurface of it. Most regions have none, and this costs a few hundred
// reads where the search costs a few morphological passes over the box.
bool mayHaveShadow(const cv::Mat& mask, const cv::Mat& grey, const std::vector<cv::Point>& outer,
                   Level* lit) {
  std::vector<float> out;
  std::vector<float> in;
  sideSamples(grey, mask, outer, &out, &in);
  if (out.size() < 8 || in.size() < 8) return false;
  // The noise first, while the samples are in their order along the
  // outline (medianOf reorders them; the counts below need no order).
  // Odd only beyond that noise, as the search asks of a layer and of the
  // ring (thickLayer, cutRegion): at 30 grey levels of contrast a quarter of
  // it is within two or three of the noise's spreads, and every region was
  // searched (a third of the region pass of such a frame, where nothing is
  // cut).
  const double in_noise = noiseAlong(in);
  const double out_noise = noiseAlong(out);
  Histogram out_levels{};
  for (const float v : out) ++out_levels[static_cast<size_t>(std::clamp(v, 0.0f, 255.0f))];
  const double part = medianOf(in);
  *lit = litSurfaceLevel(out_levels, static_cast<int>(out.size()), part, out_noise);
  const double surface = lit->level;
  const double contrast = surface - part;
  if (contrast < kMinContrast) return false;
  const double lighter = std::max(kLighterShare * contrast, kSpreadsApart * in_noise);
  const double darker = std::max(kBelowSurface * contrast, kTextureSpreads * out_noise);
  size_t odd = 0;
  for (const float v : in) odd += v > part + lighter ? 1 : 0;
  for (const float v : out) odd += v < surface - darker ? 1 : 0;
  return odd >= std::max<size_t>(kMinOddSides, (in.size() + out.size()) / 20);
}

// The lens's blur at a region's edge (a Gaussian's sigma, px; 0 when too
// few profiles were read): at every kBlurStep-th point of its outline, the
// grey levels across it, kBlurReachPx either way. A blurred step of height
// h has a steepest slope of h / (sqrt(2 pi) sigma). Each profile is read
// against its own step, so that the edge between a part and its shadow (a
// lower step) reads as sharp as its other edges; profiles stepping by less
// than kBlurStepShare of the highest steps (beside a shadow's soft outer
// edge, or the noise) are left out. The median over the outline, less the
// sampling's own blur (kSamplingBlurPx).
double edgeBlur(const cv::Mat& grey, const cv::Mat& mask, const std::vector<cv::Point>& outer) {
  const int n = static_cast<int>(outer.size());
  const auto level = [&](double x, double y) {
    const int x0 = static_cast<int>(std::floor(x));
    const int y0 = static_cast<int>(std::floor(y));
    const double fx = x - x0;
    const double fy = y - y0;
    const uint8_t* top = grey.ptr<uint8_t>(y0);
    const uint8_t* bottom = grey.ptr<uint8_t>(y0 + 1);
    return (1 - fy) * ((1 - fx) * top[x0] + fx * top[x0 + 1]) +
           fy * ((1 - fx) * bottom[x0] + fx * bottom[x0 + 1]);
  };
  // Profiles reach kBlurReachPx (and a pixel for the bilinear read) from
  // their outline point.
  const cv::Rect inside(kBlurReachPx + 1, kBlurReachPx + 1, grey.cols - 2 * kBlurReachPx - 2,
                        grey.rows - 2 * kBlurReachPx - 2);
  std::vector<float> steps;
  std::vector<float> sigmas;
  std::array<double, 2 * kBlurReachPx + 1> profile{};
  for (int i = 0; i < n; i += kBlurStep) {
    const cv::Point p = outer[static_cast<size_t>(i)];
    if (!inside.contains(p)) continue;
    const cv::Point d =
        outer[static_cast<size_t>((i + 2) % n)] - outer[static_cast<size_t>((i - 2 + n) % n)];
    const double len = std::hypot(d.x, d.y);
    if (len == 0) continue;
    cv::Point2d normal(-d.y / len, d.x / len);
    // Outwards: off the mask two pixels out.
    const cv::Point out(static_cast<int>(std::lround(p.x + 2 * normal.x)),
                        static_cast<int>(std::lround(p.y + 2 * normal.y)));
    if (mask.at<uint8_t>(out) != 0) normal = -normal;
    for (int k = -kBlurReachPx; k <= kBlurReachPx; ++k) {
      profile[static_cast<size_t>(k + kBlurReachPx)] =
          level(p.x + k * normal.x, p.y + k * normal.y);
    }
    const double step = 0.5 * (profile[profile.size() - 1] + profile[profile.size() - 2]) -
                        0.5 * (profile[0] + profile[1]);
    double steepest = 0;
    for (size_t k = 1; k + 1 < profile.size(); ++k) {
      steepest = std::max(steepest, 0.5 * (profile[k + 1] - profile[k - 1]) * (step > 0 ? 1 : -1));
    }
    if (steepest <= 0) continue;
    steps.push_back(static_cast<float>(std::abs(step)));
    sigmas.push_back(static_cast<float>(std::abs(step) / (std::sqrt(2 * M_PI) * steepest)));
  }
  if (steps.size() < kMinOddSides) return 0;
  // The highest steps: the 90th percentile.
  std::vector<float> sorted = steps;
  const auto high = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() * 9 / 10);
  std::nth_element(sorted.begin(), high, sorted.end());
  const double min_step = kBlurStepShare * *high;
  std::vector<float> kept;
  for (size_t k = 0; k < steps.size(); ++k) {
    if (steps[k] >= min_step) kept.push_back(sigmas[k]);
  }
  if (kept.size() < kMinOddSides) return 0;
  const double seen = medianOf(kept);
  return std::min(kMaxBlurPx,
                  std::sqrt(std::max(0.0, seen * seen - kSamplingBlurPx * kSamplingBlurPx)));
}

bool cutRegion(const cv::Mat& mask, const cv::Mat& grey,
               const std::vector<std::vector<cv::Point>>& contours, int i, RegionCut* cut) {
  Level lit;
  if (!mayHaveShadow(mask, grey, contours[static_cast<size_t>(i)], &lit)) return false;
  cut->blur_px = edgeBlur(grey, mask, contours[static_cast<size_t>(i)]);
  const Reaches reach = reachesFor(cut->blur_px);
  const cv::Rect frame(0, 0, mask.cols, mask.rows);
  const int margin = 2 * reach.ring_inner + 1;
  const cv::Rect box = (cv::boundingRect(contours[static_cast<size_t>(i)]) +
                        cv::Size(2 * margin, 2 * margin) - cv::Point(margin, margin)) &
                       frame;
  const cv::Mat g = grey(box);
  cv::Mat own = cv::Mat::zeros(box.size(), CV_8UC1);
  fillContour(own, contours[static_cast<size_t>(i)], cv::Scalar(255), -box.tl());
  cv::bitwise_and(own, mask(box), own);

  Levels l;
  cv::Mat interior;
  erodeDisc(own, interior, kCoreDepth);
  if (!levelsOf(g, interior, kMinShadowPixels, &l.part, &l.part_spread)) return false;
  cv::Mat near;
  cv::Mat ring;
  dilateMask(own, near, reach.ring_inner);
  // The inner disc twice makes about the outer one (40 pixels of a 220 px
  // box differ, at the ring's rim). Chosen when OpenCV's 13x13 pass cost
  // three of its 7x7 (140 against 45 us on such a box); with dilateMask a
  // disc of radius 6 costs less than two of radius 3 (26 against 2 x 19 us
  // on a 236 px box), but the ring is kept as it was, pixel for pixel.
  static_assert(kRingOuter == 2 * kRingInner, "the ring's outer disc is two inner ones");
  dilateMask(near, ring, reach.ring_inner);
  cv::bitwise_xor(ring, near, ring);
  cv::Mat free;
  cv::compare(mask(box), 0, free, cv::CMP_EQ);
  cv::bitwise_and(ring, free, ring);
  Histogram ring_levels{};
  const int ring_count = histogramOf(g, ring, &ring_levels);
  if (ring_count < kMinShadowPixels) return false;
  Level surface = medianLevel(ring_levels, ring_count);
  // Where the levels 3 px out were mostly a shadow's (litSurfaceLevel), the
  // wider ring may hold enough of the surface to leave its median above
  // the shadow but its spread across the step (a triangle under a lamp from
  // 45 degrees: median 173, spread 25, a shadow 30-45 levels under a
  // surface at 193, none of it three spreads down): the surface is then the
  // level read there, its spread that of the ring's levels above it.
  if (lit.shadowed && lit.level > surface.level) {
    const double spread = spreadAbove(ring_levels, lit.level);
    if (spread >= 0) surface = {lit.level, spread};
  }
  l.surface = surface.level;
  l.surface_spread = surface.spread;
  if (l.contrast() < kMinContrast) return false;  // a light part, or too faint

  // A thick layer inside the mask: near it, the part is what is darker
  // than halfway to the shadow's level.
  cv::Mat removed = cv::Mat::zeros(box.size(), CV_8UC1);
  cv::Mat zone = cv::Mat::zeros(box.size(), CV_8UC1);
  const cv::Mat layer = thickLayer(g, own, interior, l);
  if (!layer.empty()) {
    double level = 0;
    levelsOf(g, layer, 1, &level);
    cv::Mat reach;
    dilateMask(layer, reach, kCutReach);
    cv::bitwise_and(reach, own, reach);
    cv::Mat beyond;
    cv::compare(g, 0.5 * (l.part + level), beyond, cv::CMP_GE);
    cv::bitwise_and(reach, beyond, removed);
    own.setTo(0, removed);
    cv::bitwise_or(free, removed, free);
  }
  // What is left of a shadow outside the mask, or a thin one inside it,
  // darkens the surface's ring, 3 to 6 px out, below the surface's level by
  // more than its texture (nearer, the blur of a defocused edge darkens it
  // too: by 16 % of the contrast 2 px out of an edge blurred by 2 px).
  cv::Mat dark = ring.clone();
  const double gap = std::max(kBelowSurface * l.contrast(), kTextureSpreads * l.surface_spread);
  cv::Mat darker;
  cv::compare(g, l.surface - gap, darker, cv::CMP_LT);
  cv::bitwise_and(dark, darker, dark);
  if (layer.empty() && cv::countNonZero(dark) < kMinShadowPixels) return false;
  // A shadow's soft edge darkens the surface beside the part well beyond
  // where it shows clearly (the ring a tenth darker along an edge that runs
  // with the light moved a part by half a pixel): with a shadow, every edge
  // of the part is read against the level beside it.
  dilateMask(own, zone, reach.far_out + kZoneReach);
  const cv::Mat outside = outsideLevels(g, own, free, zone, cut->blur_px);
  // The part's pixels at least halfway from its level to the level just
  // outside: v >= (part + outside) / 2, tested as 2 v - part >= outside,
  // exact in floats as in doubles (the part's level is a whole grey level).
  const auto part = static_cast<float>(l.part);
  int thin = 0;
  for (int y = 0; y < own.rows; ++y) {
    const uint8_t* o = own.ptr<uint8_t>(y);
    const uint8_t* v = g.ptr<uint8_t>(y);
    const float* level = outside.ptr<float>(y);
    uint8_t* r = removed.ptr<uint8_t>(y);
    int x = 0;
#if CV_SIMD128
    // Sixteen pixels a step, none of the part's skipped whole: this loop
    // over the box, a pixel at a time, was 7 % of the cut (perf).
    const cv::v_float32x4 twice = cv::v_setall_f32(2.0f);
    const cv::v_float32x4 level_of_part = cv::v_setall_f32(part);
    const cv::v_float32x4 none = cv::v_setzero_f32();
    for (; x + 16 <= own.cols; x += 16) {
      const cv::v_uint8x16 in_part = cv::v_load(o + x) != cv::v_setzero_u8();
      if (!cv::v_check_any(in_part)) continue;
      const std::array<cv::v_uint32x4, 4> lanes = widened(v + x);
      std::array<cv::v_uint32x4, 4> cut;
      for (size_t q = 0; q < lanes.size(); ++q) {
        const cv::v_float32x4 grey = cv::v_cvt_f32(cv::v_reinterpret_as_s32(lanes[q]));
        const cv::v_float32x4 out = cv::v_load(level + x + 4 * static_cast<int>(q));
        cut[q] = cv::v_reinterpret_as_u32((out >= none) & (twice * grey - level_of_part >= out));
      }
      const cv::v_uint8x16 cuts =
          cv::v_pack(cv::v_pack(cut[0], cut[1]), cv::v_pack(cut[2], cut[3])) & in_part;
      cv::v_store(r + x, cv::v_load(r + x) | cuts);
      thin += static_cast<int>(cv::v_reduce_sum(cuts & cv::v_setall_u8(1)));
    }
#endif
    for (; x < own.cols; ++x) {
      const bool cut = (o[x] != 0) & (level[x] >= 0) & (2.0f * v[x] - part >= level[x]);
      r[x] |= cut ? 255 : 0;
      thin += cut ? 1 : 0;
    }
  }
  if (layer.empty() && thin == 0) return false;
  cut->removed = removed;
  cut->zone = zone;
  cut->box = box;
  return true;
}
}  // namespace

namespace {
// How a blur along a line of n pixels (cv::GaussianBlur's kernel for CV_32F
// and its default border, BORDER_REFLECT_101: an index past an end mirrored
// about it) carries each input pixel s into the output: into pixels
// first[s] to first[s] + stride - 1 with the weights at s * stride (zero
// past the line's end). `stride` is the kernel's size rounded up to four
// floats, the most pixels one input reaches (reflections included).
struct LineSpread {
  int stride = 0;
  std::vector<int> first;
  std::vector<float> weights;
};

LineSpread lineSpread(const std::vector<float>& kernel, int n) {
  const int r = static_cast<int>(kernel.size()) / 2;
  LineSpread out;
  out.stride = (static_cast<int>(kernel.size()) + 3) / 4 * 4;
  out.first.resize(static_cast<size_t>(n));
  out.weights.assign(static_cast<size_t>(n) * static_cast<size_t>(out.stride), 0.0f);
  // An input pixel reaches no output before s - r, nor before 0; its
  // reflections land within the kernel's reach of it.
  for (int s = 0; s < n; ++s) {
    out.first[static_cast<size_t>(s)] = std::max(0, std::min(s - r, n - out.stride));
  }
  // cv::borderInterpolate's BORDER_REFLECT_101, inline (a call per product
  // took as long as the sums).
  const auto reflect = [n](int i) {
    if (n == 1) return 0;
    while (i < 0 || i >= n) i = i < 0 ? -i : 2 * (n - 1) - i;
    return i;
  };
  for (int p = 0; p < n; ++p) {
    for (int k = -r; k <= r; ++k) {
      const int s = reflect(p + k);
      const int at = p - out.first[static_cast<size_t>(s)];
      CV_DbgAssert(at >= 0 && at < out.stride);
      out.weights[static_cast<size_t>(s * out.stride + at)] += kernel[static_cast<size_t>(r + k)];
    }
  }
  return out;
}
}  // namespace

cv::Mat outsideLevels(const cv::Mat& g, const cv::Mat& own, const cv::Mat& free,
                      const cv::Mat& where, double blur_px) {
  const Reaches reach = reachesFor(blur_px);
  cv::Mat inner;
  cv::Mat ring;
  dilateDisc(own, inner, reach.near_out);
  dilateDisc(own, ring, reach.far_out);
  ring.setTo(0, inner);
  cv::bitwise_and(ring, free, ring);
  cv::bitwise_and(ring, where, ring);
  // The ring is a pixel wide: each of its pixels' Gaussian is added where
  // it reaches (a few hundred products a pixel), which is the blur of the
  // ring's levels and of its weights (cv::GaussianBlur's kernel and border)
  // at a fraction of the cost of blurring both over the whole box (those
  // two blurs were a quarter of the region pass's instructions on a frame
  // of 20 parts beside cast shadows, callgrind).
  const int ksize = cvRound(reach.outside_sigma * 8 + 1) | 1;
  const cv::Mat k = cv::getGaussianKernel(ksize, reach.outside_sigma, CV_32F);
  const std::vector<float> kernel(k.begin<float>(), k.end<float>());
  const LineSpread along_x = lineSpread(kernel, ring.cols);
  const LineSpread along_y = lineSpread(kernel, ring.rows);
  // Sums over the box, wide enough for a whole stride from any first[s].
  const int width = std::max(ring.cols, along_x.stride);
  const int height = std::max(ring.rows, along_y.stride);
  cv::Mat weight = cv::Mat::zeros(height, width, CV_32F);
  cv::Mat level = cv::Mat::zeros(height, width, CV_32F);
  const size_t row_floats = weight.step1();
  // The ring's pixels, in rows as cv::findNonZero lists them (the sums
  // below are then added in the same order).
  std::vector<cv::Point> ring_pixels;
  forEachSetPixel(ring, [&](int x, int y) { ring_pixels.emplace_back(x, y); });
  for (const cv::Point& p : ring_pixels) {
    const int x = p.x;
    const int y = p.y;
    const float* wy = &along_y.weights[static_cast<size_t>(y * along_y.stride)];
    const int y0 = along_y.first[static_cast<size_t>(y)];
    float* const weight_rows = weight.ptr<float>(y0);
    float* const level_rows = level.ptr<float>(y0);
    const float* wx = &along_x.weights[static_cast<size_t>(x * along_x.stride)];
    const int x0 = along_x.first[static_cast<size_t>(x)];
    const auto value = static_cast<float>(g.at<uint8_t>(y, x));
    for (int j = 0; j < along_y.stride; ++j) {
      if (wy[j] == 0) continue;
      float* w = weight_rows + static_cast<size_t>(j) * row_floats + x0;
      float* l = level_rows + static_cast<size_t>(j) * row_floats + x0;
#if CV_SIMD128
      const cv::v_float32x4 across = cv::v_setall_f32(wy[j]);
      const cv::v_float32x4 bright = cv::v_setall_f32(wy[j] * value);
      for (int i = 0; i < along_x.stride; i += 4) {
        const cv::v_float32x4 kx = cv::v_load(wx + i);
        cv::v_store(w + i, cv::v_fma(across, kx, cv::v_load(w + i)));
        cv::v_store(l + i, cv::v_fma(bright, kx, cv::v_load(l + i)));
      }
#else
      for (int i = 0; i < along_x.stride; ++i) {
        w[i] += wy[j] * wx[i];
        l[i] += wy[j] * value * wx[i];
      }
#endif
    }
  }
  cv::Mat out(g.size(), CV_32F);
  for (int y = 0; y < out.rows; ++y) {
    const float* w = weight.ptr<float>(y);
    const float* l = level.ptr<float>(y);
    const uint8_t* in = where.ptr<uint8_t>(y);
    float* o = out.ptr<float>(y);
    int x = 0;
#if CV_SIMD128
    // Where no ring pixel is near, the weight is 0 and the quotient is
    // never kept.
    const cv::v_float32x4 least = cv::v_setall_f32(kMinOutsideWeight);
    const cv::v_float32x4 unread = cv::v_setall_f32(-1.0f);
    // Sixteen pixels a step; none of them asked for, none read.
    for (; x + 16 <= out.cols; x += 16) {
      if (!cv::v_check_any(cv::v_load(in + x) != cv::v_setzero_u8())) {
        for (int at = x; at < x + 16; at += 4) cv::v_store(o + at, unread);
        continue;
      }
      const std::array<cv::v_uint32x4, 4> lanes = widened(in + x);
      for (size_t q = 0; q < lanes.size(); ++q) {
        const int at = x + 4 * static_cast<int>(q);
        const cv::v_float32x4 sum = cv::v_load(w + at);
        const cv::v_float32x4 inside = cv::v_reinterpret_as_f32(lanes[q] != cv::v_setzero_u32());
        const cv::v_float32x4 kept = (sum >= least) & inside;
        cv::v_store(o + at, cv::v_select(kept, cv::v_load(l + at) / cv::v_max(sum, least), unread));
      }
    }
#endif
    for (; x < out.cols; ++x) {
      o[x] = in[x] != 0 && w[x] >= kMinOutsideWeight ? l[x] / w[x] : -1.0f;
    }
  }
  return out;
}

double medianOf(std::vector<float>& values) {
  if (values.empty()) return 0;
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

double percentileOf(std::vector<float>& values, double share) {
  if (values.empty()) return 0;
  const auto at = values.begin() + static_cast<std::ptrdiff_t>(
                                       std::floor(share * static_cast<double>(values.size() - 1)));
  std::nth_element(values.begin(), at, values.end());
  return *at;
}

void sideSamples(const cv::Mat& grey, const cv::Mat& mask, const std::vector<cv::Point>& outer,
                 std::vector<float>* out, std::vector<float>* in) {
  // Every this many boundary points is read, this far out and in.
  constexpr int kStep = 4;
  constexpr int kReachPx = 3;
  const int n = static_cast<int>(outer.size());
  const cv::Rect frame(0, 0, grey.cols, grey.rows);
  for (int i = 0; i < n; i += kStep) {
    const cv::Point d =
        outer[static_cast<size_t>((i + 2) % n)] - outer[static_cast<size_t>((i - 2 + n) % n)];
    const double len = std::hypot(d.x, d.y);
    if (len == 0) continue;
    const cv::Point2d normal(-d.y / len, d.x / len);
    for (const int sign : {-1, 1}) {
      const cv::Point q(static_cast<int>(std::lround(outer[static_cast<size_t>(i)].x +
                                                     sign * kReachPx * normal.x)),
                        static_cast<int>(std::lround(outer[static_cast<size_t>(i)].y +
                                                     sign * kReachPx * normal.y)));
      if (!frame.contains(q)) continue;
      (mask.at<uint8_t>(q) ? in : out)->push_back(grey.at<uint8_t>(q));
    }
  }
}

ShadowCut cutShadows(const cv::Mat& mask, const cv::Mat& grey,
                     const std::vector<std::vector<cv::Point>>& contours,
                     const std::vector<cv::Vec4i>& hierarchy, double min_area) {
  CV_Assert(mask.type() == CV_8UC1 && grey.type() == CV_8UC1 && grey.size() == mask.size());
  ShadowCut out;
  out.mask = mask;
  std::vector<int> outers;
  for (int i = 0; i < static_cast<int>(contours.size()); ++i) {
    if (hierarchy[static_cast<size_t>(i)][3] < 0 &&
        cv::boundingRect(contours[static_cast<size_t>(i)]).area() >= min_area) {
      outers.push_back(i);
    }
  }
  std::vector<RegionCut> cuts(outers.size());
  std::vector<char> found(outers.size(), 0);
  cv::parallel_for_(cv::Range(0, static_cast<int>(outers.size())), [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k) {
      found[static_cast<size_t>(k)] =
          cutRegion(mask, grey, contours, outers[static_cast<size_t>(k)],
                    &cuts[static_cast<size_t>(k)])
              ? 1
              : 0;
    }
  });
  // Applied in region order, after all were read from the mask as given.
  std::vector<float> blurs;
  for (size_t k = 0; k < cuts.size(); ++k) {
    if (!found[k]) continue;
    blurs.push_back(static_cast<float>(cuts[k].blur_px));
    if (out.shadows == 0) {
      out.mask = mask.clone();
      out.zone = cv::Mat::zeros(mask.size(), CV_8UC1);
    }
    ++out.shadows;
    cv::Mat kept = out.mask(cuts[k].box);
    kept.setTo(0, cuts[k].removed);
    cv::Mat zone = out.zone(cuts[k].box);
    cv::bitwise_or(zone, cuts[k].zone, zone);
  }
  out.blur_px = medianOf(blurs);
  return out;
}

}  // namespace picksight::vision
