// Region extraction: the boundaries of all regions first (one pass over the
// image), then per-region work limited to the region's bounding box.
#include "picksight/vision/segmentation/regions.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

#include "fill_contour.hpp"
#include "picksight/common/angles.hpp"
#include "picksight/vision/segmentation/row_runs.hpp"
#include "picksight/vision/segmentation/shadows.hpp"

namespace picksight::vision {

// Ends of a region's axis closer than this to the same distance from its
// centroid (pixels) are a tie (orientationDeg).
constexpr double kOrientationTiePx = 1.0;

double orientationDeg(const cv::Moments& m, cv::Point2d centroid,
                      const std::vector<cv::Point>& outer) {
  const double theta = 0.5 * std::atan2(2.0 * m.mu11, m.mu20 - m.mu02);
  const double cx = centroid.x;
  const double cy = centroid.y;
  const double ux = std::cos(theta);
  const double uy = std::sin(theta);
  // Which way along the axis: towards the farther boundary point.
  double forward = 0;
  double backward = 0;
  for (const auto& p : outer) {
    const double proj = (p.x - cx) * ux + (p.y - cy) * uy;
    forward = std::max(forward, proj);
    backward = std::max(backward, -proj);
  }
  double deg = theta * 180.0 / M_PI;
  // theta is in [-90, 90]. Ends within a pixel of each other (a bar, a
  // rectangle: a half-turn symmetric region) are told apart by noise from
  // frame to frame, and the region's angle would flip by half a turn; such
  // a region keeps the direction of theta itself, the same in every frame.
  if (backward > forward + kOrientationTiePx) deg += 180.0;
  return normalizeDeg(deg);
}

namespace {

// The frame's edge cuts whatever lies in a box that reaches it.
bool touchesBorder(const cv::Rect& bbox, cv::Size image) {
  return bbox.x == 0 || bbox.y == 0 || bbox.br().x == image.width || bbox.br().y == image.height;
}

// Below this relative contrast between part and background, coverage read
// from grey levels is mostly noise; the binary moments are kept.
constexpr double kMinContrast = 0.08;
// Darker backgrounds (grey levels) are not lit: see readBand.
constexpr double kMinLitBackground = 16;
// The part's level is fitted to the interior pixels within this fraction of
// the contrast of its median (readBand), when there are this many.
constexpr double kPartLevelTrim = 0.25;
constexpr double kMinPartPlanePixels = 64;
constexpr int kPartPlaneRowStep = 2;
// Parts darker than this fraction of the background's level (lit) take the
// light from the background alone.
constexpr double kMinPartLight = 0.35;
// The light across a region's box, relative to its centre, stays above
// this, or the grey levels are not trusted.
constexpr double kMinLight = 0.5;
// The band of edge pixels read from grey levels reaches this many pixels each
// side of the binary boundary (see greyMoments); it is widened while the mean
// coverage of its outermost pixels is above kMaxBandTail. A Gaussian edge of
// sigma s covers a pixel d out by about Phi(-d / s): 0.005 at 2 px for a
// sharp edge, 0.09 at 2 px and 0.025 at 3 px for sigma 1.5. (At 0.02 the
// benchmark's parts blurred by 1.5 px kept a 3-pixel band and were placed
// 0.029 px off, at 0.01 they got 4 pixels and 0.018.)
constexpr int kMinBand = 2;
constexpr int kMaxBand = 6;
constexpr double kMaxBandTail = 0.01;
// Each pixel the band takes in is read against levels that are off by
// about the surface's spread about its plane (texture, noise): over the
// contrast, that is the error each adds to the coverage, unevenly along
// the outline. A tail under kTailNoiseShare of it is left out: the part is
// then short of its outermost blur, about evenly all round (its size a
// little low, its centroid barely moved). On the front-lit benchmark, parts
// separated, blurred by 0.7 px (the band widened on the texture's bias
// alone), position RMS went from 0.040 to 0.027 px on the textured belt,
// 0.198 to 0.121 at 30 levels of contrast, 0.105 to 0.059 glossy, 0.129 to
// 0.072 on wood; blurred by 2.5 px, 0.49 to 0.42, 0.43 to 0.30, 0.25 to
// 0.20 (clean scenes, whose spread is noise, as before: 0.0094 and 0.057).
// At a share of 0.7 the blurred low-contrast parts did worse (0.33).
constexpr double kTailNoiseShare = 0.5;
// Beside a part on an uneven surface (blotches on a belt, a part shaded
// unlike its surface), no plane gives the levels a band pixel lies between:
// each is read against the mean of the background ring's pixels (and of the
// part's ring, kLocalDepthPx deep inside the band) within kLocalRadiusPx
// instead, where a side departs from its plane by over kDeparture (see
// departure). On the front-lit benchmark (4 scenes, parts separated) that
// placed parts on a textured belt 0.041 px off instead of 0.13 (their
// angle 0.031 degrees off instead of 0.22), beside cast shadows 0.082
// instead of 0.24, glossy 0.11 instead of 0.27, at 30 levels of contrast
// 0.21 instead of 0.76, on brushed metal 0.051 instead of 0.088. (By the
// angle on the belt, a radius of 3 px did worse than 8, 12 px no better.)
// On a plane and noise it would only add noise (the clean scenes' angle
// RMS 0.0127 degrees instead of 0.0102), hence the test.
constexpr int kLocalRadiusPx = 8;
constexpr int kLocalCellPx = 4;
constexpr float kLocalMinPixels = 6;
constexpr int kLocalDepthPx = 3;
constexpr int kDepartureTilePx = 16;
constexpr double kDeparture = 4;
// The part's levels read beside its edge (readLocally): shares of the
// contrast off the part's plane, towards the background's level and away.
constexpr double kPartRingTowardsBackground = 0.5;
constexpr double kPartRingAwayFromBackground = 1.0;
// The margin around a region's box for the band and the background ring
// beyond it.
constexpr int kBoxMargin = kMaxBand + 2;

// A hole whose brightest pixels lie beyond the background's level, away from
// the part's, by more than this share of the contrast shows no surface
// through the part: it is a glint (the lamp reflected by a glossy part), and
// the part is whole there. A real hole shows the surface under the part, at
// the background's level give or take its texture and noise, or darker (its
// rim blurred towards the part's, or in the part's shadow). "Brightest" is
// the hole's 99th percentile, and "beyond" also means by more than
// kGlintNoise deviations of the surface beside the part: in a large hole on
// a blotched belt, with only 30 levels of contrast, the very brightest pixel
// of thousands lies beyond half the contrast by noise alone, and its 99th
// percentile close to it. And beyond the surface's own brightest beside the
// part (its 99th percentile) by kGlintPastSurfaceShare of the contrast: a
// paving's joints are far lighter than its bricks, and a part's hole over a
// joint read 19 levels beyond the bricks' median (24 of contrast, noise
// 4.4) but 2 beyond the brightest of the surface beside the part; filled as
// a glint, it let the part's model (a slot, its hole at one end) verify
// turned end for end in a blob with a part touching it. A lamp's glint
// saturates, far past any surface the part lies on.
constexpr double kGlintPercentile = 0.99;
constexpr double kGlintNoise = 4;
constexpr double kGlintShare = 0.5;
constexpr double kGlintPastSurfaceShare = 0.25;

// The levels just outside (the background) and just inside (the part) a
// region's outer boundary: the medians of sideSamples, the deviation of the
// outside ones (from their median absolute deviation), and their level
// farthest from the part's (kGlintPercentile of them: the lightest beside a
// dark part). False when either side has no reading.
struct SideLevels {
  double background = 0;
  double part = 0;
  double background_spread = 0;
  double background_extreme = 0;
};

bool sideLevels(const cv::Mat& grey, const cv::Mat& mask, const std::vector<cv::Point>& outer,
                SideLevels* levels) {
  std::vector<float> out;
  std::vector<float> in;
  sideSamples(grey, mask, outer, &out, &in);
  if (out.empty() || in.empty()) return false;
  SideLevels& l = *levels;
  l.background = medianOf(out);
  l.part = medianOf(in);
  l.background_extreme =
      percentileOf(out, l.part < l.background ? kGlintPercentile : 1 - kGlintPercentile);
  for (float& v : out) v = std::abs(v - static_cast<float>(l.background));
  l.background_spread = 1.4826 * medianOf(out);
  return true;
}

// Whether the hole traced by `hole` is a glint (kGlintShare), given the
// levels beside its region.
bool isGlint(const cv::Mat& grey, const cv::Mat& mask, const std::vector<cv::Point>& hole,
             const SideLevels& side) {
  const double background = side.background;
  const cv::Rect box = cv::boundingRect(hole);
  cv::Mat inside = cv::Mat::zeros(box.size(), CV_8UC1);
  cv::drawContours(inside, std::vector<std::vector<cv::Point>>{hole}, 0, cv::Scalar(255),
                   cv::FILLED, cv::LINE_8, cv::noArray(), 0, -box.tl());
  // The hole's own pixels: inside its trace and not the part's.
  cv::Mat free;
  cv::compare(mask(box), 0, free, cv::CMP_EQ);
  cv::bitwise_and(inside, free, inside);
  std::vector<float> levels;
  const cv::Mat window = grey(box);
  for (int y = 0; y < inside.rows; ++y) {
    const uint8_t* in = inside.ptr<uint8_t>(y);
    const uint8_t* g = window.ptr<uint8_t>(y);
    for (int x = 0; x < inside.cols; ++x) {
      if (in[x]) levels.push_back(g[x]);
    }
  }
  if (levels.empty()) return false;
  // The darker side when parts are light (contrast > 0), else the lighter.
  const double contrast = side.part - background;
  const double level = percentileOf(levels, contrast < 0 ? kGlintPercentile : 1 - kGlintPercentile);
  const double beyond = std::abs(level - background);
  // How far past the surface's lightest beside a dark part (its darkest
  // beside a light one) the hole's level lies.
  const double past = (level - side.background_extreme) * (contrast < 0 ? 1 : -1);
  return (level - background) * contrast < 0 && beyond > kGlintShare * std::abs(contrast) &&
         beyond > kGlintNoise * side.background_spread &&
         past > kGlintPastSurfaceShare * std::abs(contrast);
}

// A least-squares plane z = a + b x + c y through grey levels, and the
// spread of the pixels it was fitted to (their second moments about their
// mean): the slope's noise is the grey noise times the spread's inverse.
struct PlaneFit {
  cv::Vec3d plane;
  cv::Matx22d spread;
  double residual = 0;  // the levels' standard deviation about the plane

  double at(cv::Point2d p) const { return plane[0] + plane[1] * p.x + plane[2] * p.y; }
};

// The plane of a part's own levels, fitted (or not) once for all band widths.
struct PartLight {
  bool tried = false;
  std::optional<PlaneFit> fit;
};

// The plane through the grey levels of `grey` (box coordinates) over the
// pixels of `runs` that `keep(y, x, level)`, on every `row_step`th row.
// False when too few or degenerate.
template <class Keep>
bool fitPlane(const cv::Mat& grey, const RowRuns& runs, Keep&& keep, PlaneFit* fit,
              int row_step = 1) {
  // Scalar sums: a 3x3 outer product per pixel costs more than the rest.
  // A row's sums in integers, without a branch: exactly the sums a double
  // would hold (whole numbers far below 2^53), a cycle an addition rather
  // than four, and no misprediction where `keep` takes and leaves pixels
  // at random (a blotched surface, a glinting part).
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0, sg = 0, sxg = 0, syg = 0, sgg = 0;
  runs.forEachRun([&](int y, int a, int b) {
    if (y % row_step != 0) return;
    const uint8_t* g = grey.ptr<uint8_t>(y);
    int64_t rn = 0, rx = 0, rxx = 0, rg = 0, rxg = 0, rgg = 0;
    for (int x = a; x < b; ++x) {
      const int64_t k = -static_cast<int64_t>(keep(y, x, g[x]));  // all ones or zero
      const int64_t v = g[x] & k;
      const int64_t kx = x & k;
      rn -= k;
      rx += kx;
      rxx += kx * x;
      rg += v;
      rxg += v * x;
      rgg += v * v;
    }
    n += static_cast<double>(rn);
    sx += static_cast<double>(rx);
    sy += y * static_cast<double>(rn);
    sxx += static_cast<double>(rxx);
    sxy += y * static_cast<double>(rx);
    syy += static_cast<double>(y) * y * static_cast<double>(rn);
    sg += static_cast<double>(rg);
    sxg += static_cast<double>(rxg);
    syg += y * static_cast<double>(rg);
    sgg += static_cast<double>(rgg);
  });
  if (n < 8) return false;
  const cv::Matx33d normal(n, sx, sy, sx, sxx, sxy, sy, sxy, syy);
  const cv::Vec3d rhs(sg, sxg, syg);
  cv::Vec3d solution;
  if (!cv::solve(normal, rhs, solution, cv::DECOMP_CHOLESKY)) return false;
  fit->plane = solution;
  // The residual sum of squares of a least-squares fit: sum g^2 - plane . rhs.
  fit->residual = std::sqrt(std::max(0.0, (sgg - solution.dot(rhs)) / std::max(1.0, n - 3)));
  fit->spread =
      cv::Matx22d(sxx - sx * sx / n, sxy - sx * sy / n, sxy - sx * sy / n, syy - sy * sy / n);
  return true;
}

// The median of the values counted in `histogram` (`count` of them), each
// bin taken as spread evenly over its unit width: a part of one grey level
// gives exactly that level.
double interpolatedMedian(const std::array<int, 256>& histogram, double count) {
  const double half = count / 2;
  double below = 0;
  for (size_t v = 0; v < histogram.size(); ++v) {
    const double here = histogram[v];
    if (below + here >= half && here > 0)
      return static_cast<double>(v) - 0.5 + (half - below) / here;
    below += here;
  }
  return 255;
}

// Raw moments up to the third order, gathered row by row: a row's sums of
// w, w x, w x^2 and w x^3 give all ten.
struct Moments10 {
  double m00 = 0, m10 = 0, m01 = 0, m20 = 0, m11 = 0, m02 = 0, m30 = 0, m21 = 0, m12 = 0, m03 = 0;

  void addRow(double y, double s0, double s1, double s2, double s3) {
    m00 += s0;
    m10 += s1;
    m01 += y * s0;
    m20 += s2;
    m11 += y * s1;
    m02 += y * y * s0;
    m30 += s3;
    m21 += y * s2;
    m12 += y * y * s1;
    m03 += y * y * y * s0;
  }

  // Pixels a..b-1 of row y, each of weight 1: the power sums in closed form
  // (exact in doubles for any image width).
  void addRun(int a, int b, int y) {
    const auto p1 = [](double n) { return n * (n - 1) / 2; };
    const auto p2 = [](double n) { return (n - 1) * n * (2 * n - 1) / 6; };
    const auto p3 = [&](double n) { return p1(n) * p1(n); };
    addRow(y, b - a, p1(b) - p1(a), p2(b) - p2(a), p3(b) - p3(a));
  }
};

// A region's runs dilated by squares, each radius made once from the one
// below it: the band of reach r needs radii r - 1, r and r + 2, and the
// next reach shares two.
class Dilations {
 public:
  explicit Dilations(const RowRuns& own) : own_(own) {}

  const RowRuns& byRadius(int r) {
    if (r <= 0) return own_;
    RowRuns& runs = cache_.at(static_cast<size_t>(r));
    if (runs.height() == 0) runs = byRadius(r - 1).dilated(1);
    return runs;
  }

 private:
  const RowRuns& own_;
  std::array<RowRuns, kMaxBand + 3> cache_;
};

// c[a..b) = value, four at a time (a part's interior is most of its box).
void fillRow(float* c, int a, int b, float value) {
  int x = a;
#if CV_SIMD128
  const cv::v_float32x4 four = cv::v_setall_f32(value);
  for (; x + 4 <= b; x += 4) cv::v_store(c + x, four);
#endif
  for (; x < b; ++x) c[x] = value;
}

// How one band width reads a region's grey levels: the background's and
// the part's levels, and the moments.
struct BandReading {
  // Levels a + b x + c y (box coordinates) of the background and of the
  // part, each as the light at that pixel shows it: a pixel's coverage is
  // (level - background) / (part - background).
  cv::Vec3d plane;
  cv::Vec3d part;
  // Of the coverage: the interior's, and the band's once summed (sumBand;
  // only for the band width kept).
  Moments10 sums;
  double tail = 0;  // mean raw coverage of the band's outermost pixels
  // The background ring's spread about its plane, over the contrast: the
  // error one band pixel's coverage may carry (see kTailNoiseShare).
  double level_noise = 0;
  RowRuns band;  // read from grey levels (other regions' pixels skipped)
  // The band's coverage, clamped to [0, 1], pixel after pixel in the order
  // forEachCoverage visits them: the coverage image is written from it.
  std::vector<float> band_coverage;

  // The part's level less the background's.
  double span(double x, double y) const {
    return (part[0] - plane[0]) + (part[1] - plane[1]) * x + (part[2] - plane[2]) * y;
  }
};

// The masks one band width is read through, over a region's box.
struct BandPixels {
  const cv::Mat& grey;  // the box of the frame
  const cv::Mat& own;   // the region's pixels
  const cv::Mat& set;   // every region's pixels
  float* raw;           // room for a row of the box
  // Beside a cast shadow (see shadows.hpp), the level just outside the
  // part that each band pixel is read against (CV_32F, -1 where the plane
  // holds); empty without a shadow.
  cv::Mat local;
  // On an uneven surface, the part's own level beside each band pixel
  // (CV_32F, -1 where the plane holds); empty elsewhere.
  cv::Mat local_part;

  // Whether other regions' pixels lie in the box (a region alone in its
  // box is read from the frame's mask itself, so `own` is `set`).
  bool shared() const { return own.data != set.data; }
};

// Coverage read from grey levels, not clamped, a run of a row at a time:
// four pixels at a time where the CPU can, with the same operations in the
// same precision on each pixel as the scalar tail, so the values are the
// same to the bit.
class RawCoverage {
 public:
  RawCoverage(const BandReading& reading, const cv::Mat& local, const cv::Mat& local_part)
      : reading_(reading),
        local_(local),
        local_part_(local_part)
#if CV_SIMD128_64F
        ,
        slope_(cv::v_setall_f64(reading.plane[1])),
        span_slope_(cv::v_setall_f64(reading.part[1] - reading.plane[1]))
#endif
  {
  }

  // raw[x - a] for pixel x of row y, x in [a, b); `g` is the row's grey levels.
  void run(const uint8_t* g, int y, int a, int b, float* raw) const {
    const BandReading& r = reading_;
    const double row_background = r.plane[0] + r.plane[2] * y;
    const double row_span = r.span(0, y);
    const double span_slope = r.part[1] - r.plane[1];
    int x = a;
    if (!local_.empty() || !local_part_.empty()) {
      // Beside a shadow, each pixel between the part's level and the
      // shadow's beside it; the part's light still follows the plane.
      const float* outside = local_.empty() ? nullptr : local_.ptr<float>(y);
      const float* inside = local_part_.empty() ? nullptr : local_part_.ptr<float>(y);
      for (; x < b; ++x) {
        const auto part =
            inside != nullptr && inside[x] >= 0
                ? inside[x]
                : static_cast<float>(row_background + r.plane[1] * x + row_span + span_slope * x);
        if (outside == nullptr) {
          const auto background = static_cast<float>(row_background + r.plane[1] * x);
          raw[x - a] = (static_cast<float>(g[x]) - background) / (part - background);
          continue;
        }
        const float background =
            outside[x] >= 0 ? outside[x] : static_cast<float>(row_background + r.plane[1] * x);
        raw[x - a] = (static_cast<float>(g[x]) - background) / (part - background);
      }
      return;
    }
#if CV_SIMD128_64F
    const cv::v_float64x2 row = cv::v_setall_f64(row_background);
    const cv::v_float64x2 span_row = cv::v_setall_f64(row_span);
    const cv::v_int32x4 step(0, 1, 2, 3);
    for (; x + 4 <= b; x += 4) {
      const cv::v_int32x4 xs = cv::v_setall_s32(x) + step;
      const cv::v_float64x2 low = cv::v_cvt_f64(xs);
      const cv::v_float64x2 high = cv::v_cvt_f64_high(xs);
      const cv::v_float32x4 background = cv::v_cvt_f32(row + slope_ * low, row + slope_ * high);
      const cv::v_float32x4 span =
          cv::v_cvt_f32(span_row + span_slope_ * low, span_row + span_slope_ * high);
      // Four bytes as four ints, read one by one: a row's run starts at any
      // byte, and a four-byte load from there is misaligned.
      const cv::v_float32x4 level =
          cv::v_cvt_f32(cv::v_int32x4(g[x], g[x + 1], g[x + 2], g[x + 3]));
      cv::v_store(raw + (x - a), (level - background) / span);
    }
#endif
    for (; x < b; ++x) {
      const auto background = static_cast<float>(row_background + r.plane[1] * x);
      const auto span = static_cast<float>(row_span + span_slope * x);
      const auto level = static_cast<float>(g[x]);
      raw[x - a] = (level - background) / span;
    }
  }

 private:
  const BandReading& reading_;
  const cv::Mat& local_;
  const cv::Mat& local_part_;
#if CV_SIMD128_64F
  cv::v_float64x2 slope_;
  cv::v_float64x2 span_slope_;
#endif
};

// f(y, x, raw) for every pixel of `runs` that is not another region's, raw
// being its coverage read from its grey level, not clamped: the per-pixel
// work of the region pass. A region alone in its box (its mask is the
// frame's) has no neighbour's pixel to skip.
template <class F>
void forEachCoverage(const BandReading& reading, const BandPixels& pixels, const RowRuns& runs,
                     F&& f) {
  const RawCoverage coverage(reading, pixels.local, pixels.local_part);
  const bool shared = pixels.shared();
  runs.forEachRun([&](int y, int a, int b) {
    coverage.run(pixels.grey.ptr<uint8_t>(y), y, a, b, pixels.raw);
    if (!shared) {
      for (int x = a; x < b; ++x) f(y, x, pixels.raw[x - a]);
      return;
    }
    const uint8_t* o = pixels.own.ptr<uint8_t>(y);
    const uint8_t* st = pixels.set.ptr<uint8_t>(y);
    for (int x = a; x < b; ++x) {
      if (st[x] && !o[x]) continue;  // a neighbour's
      f(y, x, pixels.raw[x - a]);
    }
  });
}

// The light over the region's box (see readBand): r.plane, the
// background's level, and r.part, the part's, as planes that follow one
// light fitted to the background ring and the part's interior. False where
// it cannot be read.
bool readLight(const BandPixels& pixels, const RowRuns& interior, const PlaneFit& background,
               cv::Point2d centre, double part_grey, double contrast, bool lit,
               double interior_count, PartLight* part_light, BandReading* reading) {
  BandReading& r = *reading;
  // Light falls unevenly, and a part reflects a fixed fraction of the light
  // that reaches it, as the background does: both levels follow the same
  // light, l(p) = 1 + g (p - centre) near the part. A plane fitted to each
  // gives g as its slope over its level, with a noise that shrinks with its
  // level and its spread, and the two are weighed accordingly (a black
  // background follows no light, and tells nothing of it). The background's
  // alone reads a light part on a dark background through a few dark grey
  // levels: the silhouette benchmark's parts at 150 on 20 were placed
  // 0.055 px off (RMS) that way, 0.012 now, at 210 on 60 0.027 and 0.011,
  // at 120 on 170 0.039 and 0.036; the part's plane alone placed dark parts
  // and low-contrast ones worse than the background's. Interior pixels far
  // from the median (a highlight, a mark, an edge blurred into a thin stem)
  // are left out of the part's plane.
  const double b0 = background.at(centre);
  cv::Matx22d weight = cv::Matx22d::zeros();
  cv::Vec2d weighted(0, 0);
  // Beside a cast shadow (pixels.local) the ring is part surface, part
  // shadow: a plane through it tilts towards the shadow, not with the
  // light, so the light is read from the part alone, or taken as even.
  const bool shadow = !pixels.local.empty();
  if (lit && !shadow) {
    weight += b0 * b0 * background.spread;
    weighted += b0 * (background.spread * cv::Vec2d(background.plane[1], background.plane[2]));
  }
  // Fitted once, to the first (widest) interior, on every other row (the
  // light changes slowly, and the pixels are many), and only where it
  // weighs: a dark part's light is read from the background, which weighs
  // about 20 times as much at 45 on 200 (the benchmark's default parts are
  // placed as before, at no cost).
  if (!part_light->tried) {
    part_light->tried = true;
    const double trim = kPartLevelTrim * std::abs(contrast);
    const auto like_part = [&](int, int, uint8_t v) { return std::abs(v - part_grey) <= trim; };
    PlaneFit fit;
    if ((!lit || part_grey >= kMinPartLight * b0) && interior_count >= kMinPartPlanePixels &&
        fitPlane(pixels.grey, interior, like_part, &fit, kPartPlaneRowStep)) {
      // Again, the pixels kept by their distance from that plane: where
      // the light falls across the part its levels leave the median, and
      // a trim about the median cuts the noise off one side there and not
      // the other, flattening the plane (at 30 levels of contrast and a
      // noise of 3, a bone 240 px long lying along a light gradient was
      // read 0.2-0.55 px off along its length).
      const PlaneFit first = fit;
      const auto near_plane = [&](int y, int x, uint8_t v) {
        return std::abs(v - first.at({static_cast<double>(x), static_cast<double>(y)})) <= trim;
      };
      fitPlane(pixels.grey, interior, near_plane, &fit, kPartPlaneRowStep);
      part_light->fit = fit;
    }
  }
  double p0 = part_grey;
  if (part_light->fit) {
    const PlaneFit& part = *part_light->fit;
    p0 = part.at(centre);
    weight += p0 * p0 * part.spread;
    weighted += p0 * (part.spread * cv::Vec2d(part.plane[1], part.plane[2]));
  }
  cv::Vec2d g;
  if (cv::solve(weight, weighted, g, cv::DECOMP_CHOLESKY)) {
    // The light stays well above nothing over the box (a slope fitted to a
    // few pixels may not).
    const int w = pixels.grey.cols;
    const int h = pixels.grey.rows;
    for (const cv::Point2d corner : {cv::Point2d(0, 0), cv::Point2d(w - 1, 0),
                                     cv::Point2d(0, h - 1), cv::Point2d(w - 1, h - 1)}) {
      if (1 + g.dot(cv::Vec2d(corner.x - centre.x, corner.y - centre.y)) < kMinLight) return false;
    }
    const auto lightPlane = [&](double level) {
      return cv::Vec3d(level * (1 - g[0] * centre.x - g[1] * centre.y), level * g[0], level * g[1]);
    };
    r.plane = lit ? lightPlane(b0) : background.plane;
    r.part = lightPlane(p0);
  } else if (!lit) {
    // A black background and too little interior to read the light from:
    // the part's level a fixed step above the background's.
    r.plane = background.plane;
    r.part = background.plane + cv::Vec3d(p0 - b0, 0, 0);
  } else if (shadow) {
    // A dark part beside its shadow: its interior is too dark to show the
    // light and the ring shows the shadow, so the light is taken as even
    // over the box; each band pixel is read against the level beside it
    // (pixels.local) all the same. Read through the tilted ring instead,
    // the light fell to nothing at a corner of the box of 3 of 14 parts
    // taught beside shadows, which were then measured on their binary mask
    // alone and taught 0.2 to 0.4 px off.
    r.plane = cv::Vec3d(b0, 0, 0);
    r.part = cv::Vec3d(p0, 0, 0);
  } else {
    return false;
  }
  return true;
}

// The band's coverage read from its grey levels (see readBand), clamped,
// into reading->band_coverage, and its moments added to reading->sums row
// by row. False where the band covers nothing.
bool sumBand(const BandPixels& pixels, BandReading* reading) {
  BandReading& r = *reading;
  Moments10& sums = r.sums;
  int row = -1;
  double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
  std::vector<float>& band_coverage = reading->band_coverage;
  band_coverage.clear();
  band_coverage.reserve(static_cast<size_t>(r.band.count()));
  forEachCoverage(r, pixels, r.band, [&](int y, int x, float raw) {
    if (y != row) {
      if (row >= 0) sums.addRow(row, s0, s1, s2, s3);
      row = y;
      s0 = s1 = s2 = s3 = 0;
    }
    const float clamped = std::min(std::max(raw, 0.0f), 1.0f);
    band_coverage.push_back(clamped);
    const double v = clamped;
    const double xv = x * v;
    const double xxv = xv * x;
    s0 += v;
    s1 += xv;
    s2 += xxv;
    s3 += xxv * x;
  });
  if (row >= 0) sums.addRow(row, s0, s1, s2, s3);
  return sums.m00 > 0;
}

// The mean coverage, not clamped (so that noise averages out), of the
// band's outermost pixels `rim` (see readBand).
double bandTail(const BandReading& r, const BandPixels& pixels, const RowRuns& rim) {
  double tail_sum = 0;
  int tail_count = 0;
  forEachCoverage(r, pixels, rim, [&](int, int, float raw) {
    tail_sum += raw;
    ++tail_count;
  });
  return tail_count > 0 ? tail_sum / tail_count : 0.0;
}

// Reads one region with a band of a given reach (see greyMoments below).
// Returns false when the grey levels cannot be trusted.
//
// Light falls unevenly, so a pixel's grey level is read between the levels
// the light at that pixel gives the background and the part: planes fitted
// to a ring of background around the part and to the part's interior give
// both (readLight), and a pixel's coverage is (I - background) /
// (part - background). Constant levels instead would weigh one side of a
// part more than the other and pull its centroid by a tenth of a pixel under
// a few percent of light gradient.
//
// Pixels deeper inside the binary boundary than the band (`interior`, with
// the `histogram` of its grey levels) are the part's: their coverage is 1.
// Only the band, where the edge blur is, carries sub-pixel information;
// reading the interior from grey levels too would only add its noise, and
// let a highlight or a printed mark on the part pull its centroid.
//
// The ring, the band and the interior are run sets made by square
// morphology on the region's runs, so the cost follows the boundary's length
// and not the box's area. `tail` is the mean coverage, not clamped (so that
// noise averages out), of the band's outermost pixels. The band's own
// moments are left to sumBand: the widths tried before the one kept need
// only their tail (summing each width tried cost a tenth of the region
// pass's instructions, on clean frames and beside cast shadows alike).
bool readBand(int reach, const BandPixels& pixels, const RowRuns& interior,
              const std::array<int, 256>& histogram, Dilations& dilations, PartLight* part_light,
              BandReading* reading) {
  const RowRuns& near = dilations.byRadius(reach);
  const RowRuns& nearer = dilations.byRadius(reach - 1);
  const RowRuns& far = dilations.byRadius(reach + 2);
  // Background from a ring just outside the edge blur, free of other parts.
  const cv::Mat& set = pixels.set;
  const auto free = [&](int y, int x, uint8_t) { return set.ptr<uint8_t>(y)[x] == 0; };
  PlaneFit background;
  if (!fitPlane(pixels.grey, far.minus(near), free, &background)) return false;
  BandReading& r = *reading;

  // The interior's moments, run by run in closed form.
  Moments10& sums = r.sums;
  sums = Moments10{};
  double interior_count = 0;
  interior.forEachRun([&](int y, int a, int b) {
    sums.addRun(a, b, y);
    interior_count += b - a;
  });
  if (interior_count < 8) return false;
  // The part's level: its median grey (so that a highlight or a printed mark
  // does not change the level every edge pixel is read against), against
  // the background's at the interior's centroid; below, where its own light
  // is read, its plane's level there.
  const cv::Point2d centre(sums.m10 / sums.m00, sums.m01 / sums.m00);
  const double centre_background = background.at(centre);
  const double part_grey = interpolatedMedian(histogram, interior_count);
  const double contrast = part_grey - centre_background;
  // A black background carries no light to be relative to: the contrast is
  // then judged on the grey scale.
  const bool lit = centre_background >= kMinLitBackground;
  if (std::abs(contrast) < kMinContrast * (lit ? centre_background : 255)) return false;

  if (!readLight(pixels, interior, background, centre, part_grey, contrast, lit, interior_count,
                 part_light, reading)) {
    return false;
  }
  // The band: pixels near the region, not deep inside it, never a
  // neighbour's.
  reading->band = near.minus(interior);
  reading->tail = bandTail(r, pixels, near.minus(nearer));
  reading->level_noise = background.residual / std::abs(contrast);
  return true;
}

// How far the levels of the pixels of `ring` that `keep(y, x, level)`
// depart from `plane` (box coordinates), tile by tile: the mean over
// kDepartureTilePx tiles of n m^2 / s^2, a tile's count n and mean residual
// m against the variance s^2 of all residuals. About 1 where the levels are
// the plane and white noise (fine grain is noise too: it averages out along
// a boundary); far more where blotches, a part's shading or a light the
// plane does not follow lie beside the edge.
template <class Keep>
double departure(const cv::Mat& grey, const RowRuns& ring, Keep&& keep, const cv::Vec3d& plane) {
  const int columns = grey.cols / kDepartureTilePx + 1;
  const int rows = grey.rows / kDepartureTilePx + 1;
  std::vector<double> count(static_cast<size_t>(columns * rows), 0.0);
  std::vector<double> sum(count.size(), 0.0);
  double n = 0;
  double squares = 0;
  ring.forEachRun([&](int y, int a, int b) {
    const uint8_t* g = grey.ptr<uint8_t>(y);
    const size_t row = static_cast<size_t>((y / kDepartureTilePx) * columns);
    for (int x = a; x < b; ++x) {
      if (!keep(y, x, g[x])) continue;
      const double residual = g[x] - (plane[0] + plane[1] * x + plane[2] * y);
      const size_t tile = row + static_cast<size_t>(x / kDepartureTilePx);
      count[tile] += 1;
      sum[tile] += residual;
      n += 1;
      squares += residual * residual;
    }
  });
  if (n < 2 || squares <= 0) return 0;
  const double variance = squares / n;
  double statistic = 0;
  int tiles = 0;
  for (size_t t = 0; t < count.size(); ++t) {
    if (count[t] == 0) continue;
    statistic += sum[t] * sum[t] / count[t] / variance;
    ++tiles;
  }
  return statistic / tiles;
}

// The mean level of the pixels of `ring` that `keep(y, x, level)` within
// about kLocalRadiusPx of each pixel of `band` (box coordinates of `grey`),
// into `levels` (CV_32F over the box), -1 where fewer than kLocalMinPixels
// are near; a value already set there (>= 0, beside a shadow) is kept.
// Made when empty, and then only the band's pixels are written: the band
// is all that is read of it, and filling the whole box with -1 first took
// a tenth of the region pass at 30 levels of contrast. The sums are made
// on a grid of kLocalCellPx cells, summed over the cells around and
// interpolated between cell centres:
// the level beside an edge changes over several pixels, and full-size sums
// over the box cost more than the rest of the region's reading.
template <class Keep>
void localLevels(const cv::Mat& grey, const RowRuns& ring, Keep&& keep, const RowRuns& band,
                 cv::Mat* levels) {
  const int columns = (grey.cols + kLocalCellPx - 1) / kLocalCellPx;
  const int rows = (grey.rows + kLocalCellPx - 1) / kLocalCellPx;
  cv::Mat count = cv::Mat::zeros(rows, columns, CV_32F);
  cv::Mat sum = cv::Mat::zeros(rows, columns, CV_32F);
  ring.forEachRun([&](int y, int a, int b) {
    const uint8_t* g = grey.ptr<uint8_t>(y);
    float* n = count.ptr<float>(y / kLocalCellPx);
    float* v = sum.ptr<float>(y / kLocalCellPx);
    for (int x = a; x < b; ++x) {
      if (!keep(y, x, g[x])) continue;
      n[x / kLocalCellPx] += 1;
      v[x / kLocalCellPx] += g[x];
    }
  });
  constexpr int kCells = 2 * (kLocalRadiusPx / kLocalCellPx) + 1;
  cv::boxFilter(count, count, -1, cv::Size(kCells, kCells), cv::Point(-1, -1), false,
                cv::BORDER_CONSTANT);
  cv::boxFilter(sum, sum, -1, cv::Size(kCells, kCells), cv::Point(-1, -1), false,
                cv::BORDER_CONSTANT);
  // Each column's cell to the left of it and its weight towards the next
  // one, worked out once for the box rather than for each band pixel.
  std::vector<int> left(static_cast<size_t>(grey.cols));
  std::vector<float> towards_right(static_cast<size_t>(grey.cols));
  for (int x = 0; x < grey.cols; ++x) {
    const float fx = std::clamp((x + 0.5f) / kLocalCellPx - 0.5f, 0.0f, columns - 1.0f);
    const int x0 = static_cast<int>(fx);
    left[static_cast<size_t>(x)] = x0;
    towards_right[static_cast<size_t>(x)] = fx - x0;
  }
  const bool made = levels->empty();
  if (made) levels->create(grey.size(), CV_32F);
  band.forEachRun([&](int y, int a, int b) {
    float* o = levels->ptr<float>(y);
    // Between the centres of the cells above and below, left and right.
    const float fy = std::clamp((y + 0.5f) / kLocalCellPx - 0.5f, 0.0f, rows - 1.0f);
    const int y0 = static_cast<int>(fy);
    const int y1 = std::min(y0 + 1, rows - 1);
    const float wy = fy - y0;
    const float* n0 = count.ptr<float>(y0);
    const float* n1 = count.ptr<float>(y1);
    const float* v0 = sum.ptr<float>(y0);
    const float* v1 = sum.ptr<float>(y1);
    for (int x = a; x < b; ++x) {
      if (!made && o[x] >= 0) continue;
      o[x] = -1;
      const int x0 = left[static_cast<size_t>(x)];
      const int x1 = std::min(x0 + 1, columns - 1);
      const float wx = towards_right[static_cast<size_t>(x)];
      const auto at = [&](const float* top, const float* bottom) {
        return (1 - wy) * ((1 - wx) * top[x0] + wx * top[x1]) +
               wy * ((1 - wx) * bottom[x0] + wx * bottom[x1]);
      };
      const float n = at(n0, n1);
      if (n >= kLocalMinPixels) o[x] = at(v0, v1) / n;
    }
  });
}

// On an uneven surface, reads the band of `kept` again against the levels
// just outside and just inside it (see kLocalRadiusPx), each side only where
// its levels depart from the plane read for it (departure). True when it
// did; false, `kept` unchanged, where the planes hold on both sides (the
// local levels may then be left in `pixels`, read by nothing after).
bool readLocally(int reach, const RowRuns& interior, Dilations& dilations, BandPixels* pixels,
                 BandReading* kept) {
  const RowRuns outside = dilations.byRadius(reach + 2).minus(dilations.byRadius(reach));
  const RowRuns inside = interior.minus(interior.eroded(kLocalDepthPx));
  const cv::Mat& set = pixels->set;
  const auto free = [&](int y, int x, uint8_t) { return set.ptr<uint8_t>(y)[x] == 0; };
  // The part's ring without what lies nearer the background's level than
  // its own (a glint filled in, a light mark), as a share of the contrast
  // from the part's plane towards the background's, and without what lies
  // further than the whole contrast the other way (a print darker than any
  // shade of the part). Within both stays the part's own shading: where a
  // face curves away from the lamp it may lie darker than the plane by
  // more than half the contrast, and left out there (a bound of half the
  // contrast either way, before), its edge was read against the lighter
  // level of the part further off: a bar at 30 levels of contrast, its
  // last quarter shaded down by 30 more, was placed 0.43-0.50 px towards
  // that end, now 0.05-0.12; a spoon taught at 30 levels on the
  // front-light benchmark 0.37 px off, now 0.06.
  const BandReading& r = *kept;
  const auto like_part = [&](int y, int x, uint8_t v) {
    const double part = r.part[0] + r.part[1] * x + r.part[2] * y;
    const double towards_background = (part - v) / r.span(x, y);
    return towards_background <= kPartRingTowardsBackground &&
           towards_background >= -kPartRingAwayFromBackground;
  };
  const bool surface = departure(pixels->grey, outside, free, r.plane) > kDeparture;
  const bool part = departure(pixels->grey, inside, like_part, r.part) > kDeparture;
  if (!surface && !part) return false;
  if (surface) localLevels(pixels->grey, outside, free, kept->band, &pixels->local);
  if (part) localLevels(pixels->grey, inside, like_part, kept->band, &pixels->local_part);
  BandReading reading = *kept;
  reading.sums = Moments10{};
  interior.forEachRun([&](int y, int a, int b) { reading.sums.addRun(a, b, y); });
  if (!sumBand(*pixels, &reading)) return false;
  *kept = std::move(reading);
  return true;
}

// Grey-level coverage moments of one region (see findRegions and readBand),
// and its coverage over `box` in `weights`. Returns false, leaving the
// outputs alone, when the grey levels cannot be trusted.
//
// `own` is the region's mask over `box` (the bounding box with a margin for
// the edge blur and the background ring), `set` the mask of all regions
// there.
//
// The band read from grey levels must hold the edge blur, and no more: each
// pixel of it adds its noise. A sharp edge (blur sigma under a pixel) is
// within 2 pixels of the binary boundary; a defocused one spreads further,
// and a band cut short of it leaves a part's blur tail out, unevenly where
// the part is curved or thin (sigma 1.5 px placed the benchmark's parts 0.068
// px off with 2 pixels, 0.018 with 4; sigma 2.5, 0.158 with 2 and 0.028 as
// widened). So the band starts at 2 pixels and widens while its outermost
// pixels are still measurably covered: by more than the levels they are
// read against could make up (kTailNoiseShare).
//
// `zone` (over `box`; empty where none lies in it) is where a cast shadow
// lies beside the part (see shadows.hpp): there each band pixel is read
// against the shadow's level beside it (outsideLevels, past the lens's blur
// `blur_px`), not the surface's. `uneven` tells whether the band was read
// against levels beside it (a shadow's, or readLocally's) rather than
// planes (Region::uneven_light).
bool greyMoments(const cv::Mat& grey_box, const cv::Mat& own, const RowRuns& own_runs,
                 const cv::Mat& set, const cv::Mat& zone, double blur_px, const cv::Rect& box,
                 cv::Moments* moments, cv::Point2d* centroid, cv::Mat* weights, cv::Point* origin,
                 RowRuns* covered, bool* uneven) {
  std::vector<float> raw_row(static_cast<size_t>(box.width));
  BandPixels pixels{grey_box, own, set, raw_row.data(), {}, {}};
  if (!zone.empty()) pixels.local = outsideLevels(grey_box, own, set == 0, zone, blur_px);
  Dilations dilations(own_runs);
  BandReading kept;
  int kept_reach = 0;
  RowRuns kept_interior;
  // The histogram of the interior's grey levels, made once and then
  // narrowed with the interior: a wider band's interior is the narrower
  // one's less a shell.
  std::array<int, 256> histogram{};
  // Four counts per level while counting, summed after: a part's interior
  // is mostly one level, and one count bumped pixel after pixel waits for
  // its own last store every time.
  std::array<std::array<int, 256>, 4> partial{};
  RowRuns interior;
  PartLight part_light;
  for (int reach = kMinBand; reach <= kMaxBand; ++reach) {
    // Each reach's interior is the narrower reach's eroded by one more.
    RowRuns narrower = interior.height() == 0 ? own_runs.eroded(reach) : interior.eroded(1);
    const int sign = interior.height() == 0 ? 1 : -1;
    for (auto& counts : partial) counts.fill(0);
    (sign > 0 ? narrower : interior.minus(narrower)).forEachRun([&](int y, int a, int b) {
      const uint8_t* g = grey_box.ptr<uint8_t>(y);
      int x = a;
      for (; x + 4 <= b; x += 4) {
        ++partial[0][g[x]];
        ++partial[1][g[x + 1]];
        ++partial[2][g[x + 2]];
        ++partial[3][g[x + 3]];
      }
      for (; x < b; ++x) ++partial[0][g[x]];
    });
    for (size_t v = 0; v < histogram.size(); ++v) {
      histogram[v] += sign * (partial[0][v] + partial[1][v] + partial[2][v] + partial[3][v]);
    }
    interior = std::move(narrower);
    // A wider band that cannot be read (its ring reaches a neighbour or the
    // frame's edge) leaves the narrower one's reading.
    BandReading reading;
    if (!readBand(reach, pixels, interior, histogram, dilations, &part_light, &reading)) break;
    const bool wide_enough =
        reading.tail <= std::max(kMaxBandTail, kTailNoiseShare * reading.level_noise);
    kept = std::move(reading);
    kept_reach = reach;
    kept_interior = interior;
    if (wide_enough) break;
  }
  if (kept_reach == 0) return false;
  // The band of the width kept summed once: by readLocally where it reads
  // the band again against local levels, else here.
  const bool local = readLocally(kept_reach, kept_interior, dilations, &pixels, &kept);
  if (!local && !sumBand(pixels, &kept)) return false;
  *uneven = local || !pixels.local.empty();

  // The coverage of the band width kept: 1 in the interior, read in the band,
  // 0 elsewhere; the interior and the band make up the covered runs, so
  // every pixel is written once.
  const RowRuns& covered_runs = dilations.byRadius(kept_reach);
  cv::Mat coverage(box.size(), CV_32F);
  int zero_row = 0;  // pixels before (zero_x, zero_row) in raster order are written
  int zero_x = 0;
  const auto zeroUpTo = [&](int y, int x) {
    for (; zero_row < y; ++zero_row, zero_x = 0) {
      fillRow(coverage.ptr<float>(zero_row), zero_x, coverage.cols, 0.0f);
    }
    fillRow(coverage.ptr<float>(y), zero_x, x, 0.0f);
  };
  covered_runs.forEachRun([&](int y, int a, int b) {
    zeroUpTo(y, a);
    zero_x = b;
  });
  if (coverage.rows > 0) zeroUpTo(coverage.rows - 1, coverage.cols);
  kept_interior.forEachRun(
      [&](int y, int a, int b) { fillRow(coverage.ptr<float>(y), a, b, 1.0f); });
  // The band's pixels in the order they were read (neighbours' skipped).
  const float* value = kept.band_coverage.data();
  const bool shared = pixels.shared();
  kept.band.forEachRun([&](int y, int a, int b) {
    float* c = coverage.ptr<float>(y);
    if (!shared) {
      std::copy(value, value + (b - a), c + a);
      value += b - a;
      return;
    }
    const uint8_t* o = own.ptr<uint8_t>(y);
    const uint8_t* st = set.ptr<uint8_t>(y);
    for (int x = a; x < b; ++x) c[x] = st[x] && !o[x] ? 0.0f : *value++;
  });
  const Moments10& s = kept.sums;
  *moments = cv::Moments(s.m00, s.m10, s.m01, s.m20, s.m11, s.m02, s.m30, s.m21, s.m12, s.m03);
  *centroid = cv::Point2d(box.x + s.m10 / s.m00, box.y + s.m01 / s.m00);
  *weights = coverage;
  *origin = box.tl();
  *covered = covered_runs;
  return true;
}

// The holes of region `i` (contour indices) that are glints (isGlint).
std::vector<int> glintHoles(const cv::Mat& mask, const cv::Mat& grey,
                            const std::vector<std::vector<cv::Point>>& contours,
                            const std::vector<cv::Vec4i>& hierarchy, int i) {
  std::vector<int> glints;
  if (grey.empty() || hierarchy[i][2] < 0) return glints;
  SideLevels side;
  if (!sideLevels(grey, mask, contours[i], &side)) return glints;
  for (int h = hierarchy[i][2]; h >= 0; h = hierarchy[h][0]) {
    if (isGlint(grey, mask, contours[h], side)) glints.push_back(h);
  }
  return glints;
}

// A hole of at most kMaxPinholePx x kMaxPinholePx pixels is not the part's:
// a defective pixel of the sensor (a hot pixel in a dark part), a speck of
// dust on the lens or JPEG ringing at a sharp corner of the part's face.
// No hole that small can be told from those (the lens's blur alone spreads
// a point over it), and counted, it refuses the part: a photograph of six
// bars on a light table (tests/data/scenes/pca_test1.jpg) shows one bar
// with a single pixel of level 107 inside, the bar at 10 and the table at
// 230. Its border (the part's pixels round it) lies in a box two pixels
// larger.
constexpr int kMaxPinholePx = 2;

bool isPinhole(const std::vector<cv::Point>& border) {
  const cv::Rect b = cv::boundingRect(border);
  return b.width <= kMaxPinholePx + 2 && b.height <= kMaxPinholePx + 2;
}

// Measures the region whose outer boundary is contours[i] (see
// findRegions) into `region`: its pixels over its box (alone in its box, or
// the set pixels connected to its boundary), holes (glints and pinholes left out), moments
// (grey-level where they can be trusted), orientation and elongation. Moves its contours out.
// False, nothing written, for a region smaller than options.min_area.
bool measureRegion(const cv::Mat& mask, const cv::Mat& grey, const cv::Mat& zone, double blur_px,
                   const RegionOptions& options, std::vector<std::vector<cv::Point>>& contours,
                   const std::vector<cv::Vec4i>& hierarchy, const std::vector<cv::Rect>& boxes,
                   int i, Region* region) {
  const cv::Rect frame(0, 0, mask.cols, mask.rows);
  const cv::Rect bbox = boxes[static_cast<size_t>(i)];
  // The box the grey-level moments need: the edge blur and a background
  // ring around the region.
  const cv::Rect box =
      (bbox + cv::Size(2 * kBoxMargin, 2 * kBoxMargin) - cv::Point(kBoxMargin, kBoxMargin)) & frame;
  bool alone = true;
  for (size_t j = 0; j < boxes.size() && alone; ++j) {
    alone = static_cast<int>(j) == i || hierarchy[j][3] >= 0 || (boxes[j] & box).empty();
  }
  // Glints and pinholes are not holes: the part is whole under them, and
  // is read so (filled in the region's mask and in the mask of every
  // region).
  const std::vector<int> glints = glintHoles(mask, grey, contours, hierarchy, i);
  std::vector<int> filled = glints;
  for (int h = hierarchy[i][2]; h >= 0; h = hierarchy[h][0]) {
    if (isPinhole(contours[h]) && std::find(glints.begin(), glints.end(), h) == glints.end()) {
      filled.push_back(h);
    }
  }
  cv::Mat set = mask(box);
  if (!filled.empty()) {
    set = set.clone();
    for (const int h : filled) {
      fillContour(set, contours[static_cast<size_t>(h)], cv::Scalar(255), -box.tl());
    }
  }
  // The region's pixels over the box: the set pixels 8-connected to its
  // boundary (islands in its holes and neighbours are other regions).
  RowRuns own_runs = RowRuns::ofMask(set);
  cv::Mat own = set;
  if (!alone) {
    own_runs = own_runs.connectedTo(contours[i][0] - box.tl());
    own = own_runs.toMask();
  }
  const cv::Mat inner = own(bbox - box.tl());
  // The region's pixels are all in its bounding box, so its runs over
  // the wider box count them.
  if (static_cast<double>(own_runs.count()) < options.min_area) return false;
  const bool border = touchesBorder(bbox, mask.size());
  // Kept at the edge only for the parts it may hold (border_min_area).
  if (border && !options.keep_border_regions &&
      static_cast<double>(own_runs.count()) < options.border_min_area) {
    return false;
  }

  Region& r = *region;
  r.bbox = bbox;
  r.touches_border = border;
  r.image_size = mask.size();
  r.outer = std::move(contours[i]);
  for (int h = hierarchy[i][2]; h >= 0; h = hierarchy[h][0]) {
    if (options.min_hole_area > 0 && cv::contourArea(contours[h]) < options.min_hole_area) continue;
    if (std::find(filled.begin(), filled.end(), h) != filled.end()) continue;
    r.hole_boundaries.push_back(std::move(contours[h]));
  }
  r.holes = static_cast<int>(r.hole_boundaries.size());
  r.glints = static_cast<int>(glints.size());
  r.pinholes = static_cast<int>(filled.size() - glints.size());

  // A shadow cut off a part lies within its box (its zone: the shadow and
  // a few pixels round it).
  r.beside_shadow = !zone.empty() && cv::countNonZero(zone(box)) > 0;
  if (!grey.empty() &&
      greyMoments(grey(box), own, own_runs, set, r.beside_shadow ? zone(box) : cv::Mat(), blur_px,
                  box, &r.moments, &r.centroid, &r.coverage, &r.coverage_origin, &r.covered,
                  &r.uneven_light)) {
    r.area = r.moments.m00;
  } else {
    // Binary moments only where the grey levels cannot be trusted.
    const cv::Moments m = cv::moments(inner, true);
    r.moments = m;
    r.area = m.m00;
    r.centroid = cv::Point2d(bbox.x + m.m10 / m.m00, bbox.y + m.m01 / m.m00);
    inner.convertTo(r.coverage, CV_32F, 1.0 / 255.0);
    r.coverage_origin = bbox.tl();
    r.covered = RowRuns::ofMask(inner);
  }
  r.angle_deg = orientationDeg(r.moments, r.centroid, r.outer);
  const cv::Moments& rm = r.moments;
  const double common =
      std::sqrt((rm.mu20 - rm.mu02) * (rm.mu20 - rm.mu02) + 4 * rm.mu11 * rm.mu11);
  const double major = rm.mu20 + rm.mu02 + common;
  const double minor = rm.mu20 + rm.mu02 - common;
  r.elongation = major > 0 ? 1.0 - minor / major : 0;
  return true;
}

// A region whose outline is nowhere a step is a patch of the surface's own
// light that the threshold took in (a vignetted corner, a blotch of a
// textured belt, under front light), not parts: read kOutlineStepReachPx
// either side of its outline, a part's levels differ by tens of grey levels
// (13 to 36 on the front-light benchmark's 30-level contrast, touching and
// separated), such a patch's by 2 to 4. One such patch cost a low-contrast
// frame 17 ms in the blob search, its 24 edge fits, none placed. A region
// steps when at least kMinOutlineSteppedShare of its outline steps by
// kOutlineMinStep: a part in it takes up more of its outline than that,
// while noise of 3 grey levels steps so across 8 % of a flat patch's.
constexpr int kStepEveryPx = 4;

}  // namespace

int stepAcrossOutline(const std::vector<cv::Point>& outline, int i, const cv::Mat& grey,
                      cv::Point grey_origin, int reach_px) {
  const int n = static_cast<int>(outline.size());
  const cv::Point d =
      outline[static_cast<size_t>((i + 2) % n)] - outline[static_cast<size_t>((i - 2 + n) % n)];
  const double length = std::hypot(d.x, d.y);
  if (length == 0) return -1;
  const cv::Point2d across(-d.y / length * reach_px, d.x / length * reach_px);
  const cv::Point2d at = outline[static_cast<size_t>(i)];
  const cv::Point a(static_cast<int>(std::lround(at.x + across.x)),
                    static_cast<int>(std::lround(at.y + across.y)));
  const cv::Point b(static_cast<int>(std::lround(at.x - across.x)),
                    static_cast<int>(std::lround(at.y - across.y)));
  const cv::Rect box(grey_origin, grey.size());
  if (!box.contains(a) || !box.contains(b)) return -1;
  return std::abs(static_cast<int>(grey.at<uint8_t>(a - grey_origin)) -
                  static_cast<int>(grey.at<uint8_t>(b - grey_origin)));
}

bool outlineSteps(const Region& r, double min_share) {
  if (r.grey.empty()) return true;
  int read = 0;
  int stepped = 0;
  for (int i = 0; i < static_cast<int>(r.outer.size()); i += kStepEveryPx) {
    const int step = stepAcrossOutline(r.outer, i, r.grey, r.grey_origin, kOutlineStepReachPx);
    if (step < 0) continue;
    ++read;
    stepped += step >= kOutlineMinStep ? 1 : 0;
  }
  return read == 0 || stepped >= min_share * read;
}

double unevenEdgeShare(const cv::Mat& grey, const cv::Mat& mask, const Region& region) {
  // A quarter of the contrast: well beyond noise and a belt's texture, well
  // within a shadow's depth.
  constexpr double kUnevenShare = 0.25;
  std::vector<float> out;
  std::vector<float> in;
  sideSamples(grey, mask, region.outer, &out, &in);
  if (out.empty() || in.empty()) return 0;
  std::vector<float> sorted_out = out;
  std::vector<float> sorted_in = in;
  const double background = medianOf(sorted_out);
  const double part = medianOf(sorted_in);
  const double contrast = part - background;
  if (std::abs(contrast) < 1) return 0;
  size_t uneven = 0;
  // Towards the part's level from the surface's, or away from the part's
  // towards the surface's, by the share.
  for (const float v : out) uneven += (v - background) / contrast > kUnevenShare ? 1 : 0;
  for (const float v : in) uneven += (part - v) / contrast > kUnevenShare ? 1 : 0;
  return static_cast<double>(uneven) / static_cast<double>(out.size() + in.size());
}

std::vector<Region> findRegions(const cv::Mat& mask, const RegionOptions& options,
                                const cv::Mat& grey) {
  CV_Assert(mask.type() == CV_8UC1);
  CV_Assert(grey.empty() || (grey.type() == CV_8UC1 && grey.size() == mask.size()));
  // One boundary trace of the whole mask instead of labelling it: labels cost
  // as much again as the trace, and every region needs its boundary anyway.
  // RETR_CCOMP: outer boundaries on top, each with its holes as children.
  std::vector<std::vector<cv::Point>> contours;
  std::vector<cv::Vec4i> hierarchy;
  cv::findContours(mask, contours, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE);
  // Shadows cut off the parts they joined, and the boundaries traced again
  // (only then: most frames have none).
  ShadowCut shadows;
  if (!grey.empty() && options.cut_shadows) {
    shadows = cutShadows(mask, grey, contours, hierarchy, options.min_area);
    if (shadows.shadows > 0) {
      contours.clear();
      hierarchy.clear();
      cv::findContours(shadows.mask, contours, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE);
    }
  }
  const cv::Mat& cut = shadows.shadows > 0 ? shadows.mask : mask;
  std::vector<int> outers;
  // Boxes of every region, noise too: a region whose box meets no other
  // region's box owns every set pixel of its box, and needs no labelling.
  std::vector<cv::Rect> boxes(contours.size());
  for (int i = 0; i < static_cast<int>(contours.size()); ++i) {
    if (hierarchy[i][3] < 0) boxes[static_cast<size_t>(i)] = cv::boundingRect(contours[i]);
  }
  for (int i = 0; i < static_cast<int>(contours.size()); ++i) {
    if (hierarchy[i][3] >= 0) continue;  // a hole
    const cv::Rect bbox = boxes[static_cast<size_t>(i)];
    if (bbox.area() < options.min_area) continue;  // fewer pixels than that, surely
    const bool border = touchesBorder(bbox, mask.size());
    if (border && !options.keep_border_regions &&
        !(options.border_min_area > 0 && bbox.area() >= options.border_min_area)) {
      continue;
    }
    outers.push_back(i);
  }
  // Regions are measured independently, on all cores (the labelling this
  // replaces ran on all cores too); each writes only its own slot and its
  // own contours, so the result does not depend on the scheduling.
  std::vector<Region> found(outers.size());
  std::vector<char> kept(outers.size(), 0);
  cv::parallel_for_(cv::Range(0, static_cast<int>(outers.size())), [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k) {
      const int i = outers[static_cast<size_t>(k)];
      kept[static_cast<size_t>(k)] =
          measureRegion(cut, grey, shadows.zone, shadows.blur_px, options, contours, hierarchy,
                        boxes, i, &found[static_cast<size_t>(k)])
              ? 1
              : 0;
    }
  });
  std::vector<Region> regions;
  regions.reserve(found.size());
  for (size_t k = 0; k < found.size(); ++k) {
    if (kept[k]) regions.push_back(std::move(found[k]));
  }
  if (!grey.empty()) {
    const cv::Rect image(0, 0, grey.cols, grey.rows);
    for (auto& r : regions) {
      const cv::Rect box =
          cv::Rect(r.bbox.x - kGreyMarginPx, r.bbox.y - kGreyMarginPx,
                   r.bbox.width + 2 * kGreyMarginPx, r.bbox.height + 2 * kGreyMarginPx) &
          image;
      // A frame on memory OpenCV does not own (a received message) may be
      // gone before the regions are.
      r.grey = grey.u ? grey(box) : grey(box).clone();
      r.grey_origin = box.tl();
    }
  }
  std::stable_sort(regions.begin(), regions.end(),
                   [](const Region& a, const Region& b) { return a.area > b.area; });
  return regions;
}

}  // namespace picksight::vision
