// Part model training: body features, stability of the Hu invariants under
// rotation, boundary primitives snapped to the edges, orientation order and
// symmetries; and the preparation of a model's derived data.
#include "picksight/vision/training/part_training.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <utility>

#include "picksight/common/angles.hpp"
#include "picksight/vision/blob_search/touching_parts.hpp"
#include "picksight/vision/segmentation/shadows.hpp"

namespace picksight::vision {
namespace {
constexpr int kMaxOrder = kMaxModelOrder;
// Relative strength |c_k| / sum w |z|^k an orientation order needs. Below it
// the phase of c_k is mostly pixel noise.
constexpr double kMinOrderStrength = 0.05;
constexpr double kWeakOrderStrength = 0.01;
// Higher orders weigh the rim ever more, where noise and small defects sit.
constexpr int kMaxPreferredOrder = 6;
// Fraction of the boundary that must coincide with itself turned (or
// mirrored) for the part to count as symmetric.
constexpr double kSymmetryScore = 0.97;
// Boundary length (pixels, weighted as in handednessWeight) by which a part
// must differ from its mirror image, however it is turned, to count as
// chiral: a 5 x 5 px notch differs by ~8 px, a symmetric part's fitted
// primitives from their mirror images by well under one.
constexpr double kMinChiralLength = 3.0;
// Turns of the training image that measure how stable each Hu invariant is.
constexpr double kProbeTurnsDeg[] = {23, 67, 141, 212, 299};
// An invariant whose log changes by more than this under a turn is noise.
constexpr double kMaxHuSpread = 1.0;
constexpr double kMinHuTolerance = 0.5;
// Invariants below 1e-7 (H above 7) are what a symmetry makes 0: what is
// measured is pixel noise, of random sign (a 100 px part resolves normalized
// moments to ~1e-4, their products to ~1e-8).
constexpr double kMaxLogHu = 7.0;

// |c_k| / sum w |z|^k for k = 0..kMaxOrder, and arg c_k (degrees).
void complexMoments(const Region& r, std::vector<double>* strength,
                    std::vector<double>* phase_deg) {
  std::vector<std::complex<double>> c(kMaxOrder + 1, {0, 0});
  std::vector<double> a(kMaxOrder + 1, 0);
  const double scale = 1.0 / std::sqrt(std::max(r.area, 1.0));
  for (int y = 0; y < r.coverage.rows; ++y) {
    const float* row = r.coverage.ptr<float>(y);
    for (int x = 0; x < r.coverage.cols; ++x) {
      if (row[x] <= 0) continue;
      const std::complex<double> z((r.coverage_origin.x + x - r.centroid.x) * scale,
                                   (r.coverage_origin.y + y - r.centroid.y) * scale);
      const double m = std::abs(z);
      std::complex<double> p(1, 0);
      double pm = 1;
      for (int k = 0; k <= kMaxOrder; ++k) {
        c[k] += static_cast<double>(row[x]) * p;
        a[k] += row[x] * pm;
        p *= z;
        pm *= m;
      }
    }
  }
  strength->assign(kMaxOrder + 1, 0);
  phase_deg->assign(kMaxOrder + 1, 0);
  for (int k = 0; k <= kMaxOrder; ++k) {
    (*strength)[k] = a[k] > 0 ? std::abs(c[k]) / a[k] : 0;
    (*phase_deg)[k] = std::arg(c[k]) * 180.0 / M_PI;
  }
}

// A boundary fitted to the edges puts the part's centroid a few tenths of a
// pixel off where the snap to the edges could not move a primitive (short
// edges, thin stems): every pose found from the edges (parts that touch)
// would inherit it. The boundary is moved, once, so that the fit to the
// training edges puts the model's origin on the trained centroid.
constexpr double kMaxCentringPx = 1.0;
constexpr double kMaxCentringDeg = 1.0;

// Under uneven light (Region::uneven_light) a part's origin is the centroid
// of the area its edges enclose, not of its grey levels: each rim pixel's
// coverage is read against levels that blotches, shading, glints and
// vignetting leave uncertain by a few percent of the contrast, and summed
// over a band two or three pixels wide that error moves the centroid of one
// teach image by tenths of a pixel, which every part found with the model
// inherits; the edges' half-way crossings move far less. Front-light
// benchmark, each type taught on a whole frame, parts anywhere in it, 3
// scenes, position RMS separated / touching, grey centroid against edges:
// textured 0.026 / 0.025 -> 0.016 / 0.019 px, beside shadows 0.065 / 0.063
// -> 0.054 / 0.055, glossy 0.068 / 0.063 -> 0.036 / 0.035, wood 0.073 /
// 0.067 -> 0.054 / 0.053, brushed metal 0.041 / 0.044 -> 0.029 / 0.029,
// colour 0.034 / 0.040 -> 0.030 / 0.036, photographed bricks 0.130 / 0.129
// -> 0.084 / 0.087; at 30 levels, touching, 0.098 -> 0.065. On photographed
// gravel 0.47 / 0.44 -> 0.61 / 0.60: the stones joined to a part's outline
// in its teach image move either. Under even light the grey levels are
// read against a plane and the centroid of their coverage is the better:
// the crossings of a sampled edge stray by a few hundredths of a pixel
// with its phase (0.0102 -> 0.0147 px on clean scenes, had the edges been
// used there). An outline centroid further than this from the grey one
// read a region the model does not fit: the grey one stays.
constexpr double kMaxOutlineShiftPx = 1.0;

void centreOnEdges(PartModel& m, const Region& r) {
  const EdgeFit fit = refinePoseOnEdges(m, r, {r.centroid, 0.0, false});
  if (!fit.ok) return;
  // Model point p lies on the edges at centroid + delta + R(e) p: in the
  // model frame, at delta + R(e) p.
  const cv::Point2d delta = fit.pose.centre - r.centroid;
  const double e = signedDeg(fit.pose.angle_deg);
  if (std::hypot(delta.x, delta.y) > kMaxCentringPx || std::abs(e) > kMaxCentringDeg) return;
  moveBoundary(m, e, delta);
}

// A stretch of the trained boundary is trusted as far as the training
// image's edge there is as strong as the part's edge elsewhere. Under front
// light a blotch of the surface as dark as the part joins it in the mask:
// its outline is an edge of the surface's texture, a fraction of the
// part's contrast, and no other copy of the part shows it; counted at full
// weight, it put copies off the background test of the blob search.
// The contrast is read across the boundary kContrastProbePx either way, on
// the image smoothed over 3 x 3 pixels; a primitive whose median contrast
// is below kFullContrastShare of the whole boundary's median has its weight
// cut in proportion, to no less than kMinEdgeWeight.
constexpr double kContrastProbePx = 2.0;
constexpr double kFullContrastShare = 0.6;
constexpr double kMinEdgeWeight = 0.1;
constexpr int kMinContrastSamples = 4;

// The same within a primitive: a stretch of at least kMinWeakRun points
// (one a pixel, counted along the whole loop) each under
// kFullContrastShare of the boundary's median contrast is a stone of a
// gravel bed joined to the part, a few pixels of a primitive whose other
// points lie on the part's edge (the primitive's median does not see it).
// Its points weigh kMinEdgeWeight (Primitive::edge_weights_pct). Weighed
// by their own contrast instead (about a third of the part's, two thirds
// of kFullContrastShare), they still put a part 4 to 5 % of whose
// boundary they are on the background in the blob search's eyes:
// front-light benchmark, gravel, 14 unseen types, 3 scenes (the edge fit
// weighing them too), touching parts found 0.826 without the stretches,
// 0.913 weighed by their contrast, 0.957 and 0.978 by its square and
// fourth power, 1.000 at kMinEdgeWeight; overlapping 0.833, 0.917, 0.917,
// 0.938, 0.958. Lone weak points are the noise of the readings; a stretch
// longer than kMaxWeakRun is the part's own faint side (a shadow cut off
// beside it, its shading), which its primitives' weights already say:
// weighed at the least too, the benchmark's parts beside shadows were
// placed 0.062 -> 0.068 px RMS off (touching), 0.077 -> 0.082
// (overlapping); with the bound as before, gravel as above.
constexpr int kMinWeakRun = 3;
constexpr int kMaxWeakRun = 24;
// Where a stone's outline meets the part's the probes straddle both, and
// the contrast climbs over a point or so: the stretch is taken this many
// points wider each way. Gravel, 8 scenes, the edge fit weighing the
// stretches too (it does not, Primitive::edge_weights_pct): touching /
// overlapping found 0.966 / 0.974 without, 0.983 / 0.974 with 1 point,
// 0.983 / 0.965 with 2.
constexpr size_t kWeakMargin = 1;

// `contrastAt(p, t)`: the contrast across primitive p at t, negative where
// it is not read (off the image).
template <typename ContrastAt>
void weighWeakStretches(PartModel& m, double whole, ContrastAt&& contrastAt) {
  for (auto& loop : m.loops) {
    // Every point of the loop in order: its primitive, its index there,
    // whether it is weak.
    struct Point {
      size_t primitive;
      size_t index;
      bool weak;
    };
    std::vector<Point> points;
    for (size_t i = 0; i < loop.primitives.size(); ++i) {
      const Primitive& p = loop.primitives[i];
      const int count = edgeOffsetCount(p.length());
      for (int j = 0; j < count; ++j) {
        const double c = contrastAt(p, (j + 0.5) / count);
        points.push_back({i, static_cast<size_t>(j), c >= 0 && c < kFullContrastShare * whole});
      }
    }
    const size_t n = points.size();
    const auto weak = [&](size_t i) { return points[i % n].weak; };
    // From a point that is not weak, once round the loop (a loop weak all
    // round: its primitives' weights say it).
    size_t first = 0;
    while (first < n && weak(first)) ++first;
    if (first == n) continue;
    std::vector<char> stone(n, 0);
    for (size_t i = first + 1; i < first + n; ++i) {
      if (!weak(i)) continue;
      size_t end = i;
      while (end < first + n && weak(end)) ++end;
      const size_t run = end - i;
      if (run >= static_cast<size_t>(kMinWeakRun) && run <= static_cast<size_t>(kMaxWeakRun)) {
        for (size_t j = i + n - kWeakMargin; j < end + n + kWeakMargin; ++j) stone[j % n] = 1;
      }
      i = end;
    }
    for (size_t j = 0; j < n; ++j) {
      if (!stone[j]) continue;
      Primitive& p = loop.primitives[points[j].primitive];
      if (!(kMinEdgeWeight < p.weight)) continue;
      if (p.edge_weights_pct.empty())
        p.edge_weights_pct.assign(static_cast<size_t>(edgeOffsetCount(p.length())), 100);
      p.edge_weights_pct[points[j].index] =
          static_cast<uint8_t>(std::lround(100 * kMinEdgeWeight / p.weight));
    }
  }
}

void weighByContrast(PartModel& m, const cv::Mat& grey, cv::Point2d origin) {
  cv::Mat smooth;
  grey.convertTo(smooth, CV_32F);
  cv::blur(smooth, smooth, cv::Size(3, 3));
  const cv::Point2d last(smooth.cols - 1, smooth.rows - 1);
  const auto level = [&](cv::Point2d p) { return bilinearAt(smooth, p.x, p.y, last, -1.f); };
  // The contrast across the primitive at t (negative: off the image).
  const auto contrastAt = [&](const Primitive& p, double t) {
    const double dt = 0.5 / std::max(p.length(), 1.0);
    const cv::Point2d along = p.pointAt(std::min(1.0, t + dt)) - p.pointAt(std::max(0.0, t - dt));
    const double n = std::hypot(along.x, along.y);
    if (n <= 0) return -1.0;
    const cv::Point2d normal(-along.y / n, along.x / n);
    const cv::Point2d at = p.pointAt(t) + origin;
    const float a = level(at + kContrastProbePx * normal);
    const float b = level(at - kContrastProbePx * normal);
    if (a < 0 || b < 0) return -1.0;
    return static_cast<double>(std::abs(a - b));
  };
  std::vector<std::vector<float>> per_primitive;
  std::vector<float> all;
  for (const auto& loop : m.loops) {
    for (const auto& p : loop.primitives) {
      std::vector<float> contrast;
      const int steps = static_cast<int>(std::floor(p.length()));
      for (int i = 1; i < steps; ++i) {
        const double c = contrastAt(p, static_cast<double>(i) / steps);
        if (c >= 0) contrast.push_back(static_cast<float>(c));
      }
      all.insert(all.end(), contrast.begin(), contrast.end());
      per_primitive.push_back(std::move(contrast));
    }
  }
  const double whole = medianOf(all);
  if (!(whole > 0)) return;
  size_t k = 0;
  for (auto& loop : m.loops) {
    for (auto& p : loop.primitives) {
      auto& contrast = per_primitive[k++];
      if (static_cast<int>(contrast.size()) < kMinContrastSamples) continue;
      const double share = medianOf(contrast) / whole;
      p.weight = std::clamp(share / kFullContrastShare, kMinEdgeWeight, 1.0);
    }
  }
  weighWeakStretches(m, whole, contrastAt);
  prepareModel(m);
}

std::vector<std::vector<cv::Point>> contoursOf(const Region& r) {
  std::vector<std::vector<cv::Point>> all{r.outer};
  all.insert(all.end(), r.hole_boundaries.begin(), r.hole_boundaries.end());
  return all;
}

// Log Hu invariants of the part turned by `deg` about its centroid.
bool turnedLogHu(const cv::Mat& grey, const Region& r, double deg, const TrainOptions& options,
                 HuArray* out) {
  double reach = 0;
  for (const auto& p : r.outer)
    reach = std::max(reach, std::hypot(p.x - r.centroid.x, p.y - r.centroid.y));
  const int half = static_cast<int>(std::ceil(reach)) + 12;
  const cv::Point c(static_cast<int>(std::lround(r.centroid.x)),
                    static_cast<int>(std::lround(r.centroid.y)));
  cv::Mat padded;
  cv::copyMakeBorder(grey, padded, half, half, half, half, cv::BORDER_REPLICATE);
  const cv::Mat window = padded(cv::Rect(c.x, c.y, 2 * half + 1, 2 * half + 1));
  const cv::Point2f centre(static_cast<float>(r.centroid.x - c.x + half),
                           static_cast<float>(r.centroid.y - c.y + half));
  cv::Mat turned;
  cv::warpAffine(window, turned, cv::getRotationMatrix2D(centre, -deg, 1.0), window.size(),
                 cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  BinarizeOptions b = options.binarize;
  b.method = ThresholdMethod::kOtsu;
  RegionOptions ro = options.regions;
  ro.keep_border_regions = true;
  const auto regions = findRegions(binarize(turned, b), ro, turned);
  if (regions.empty()) return false;
  *out = logHu(huInvariants(regions.front().moments));
  return true;
}

// The orientation order and phase of a model trained on region `r`.
void setOrientation(PartModel& m, const Region& r) {
  // Orientation order: the lowest whose complex moment has a direction.
  std::vector<double> strength;
  std::vector<double> phase;
  complexMoments(r, &strength, &phase);
  // Among the orders with a clear direction, the one whose phase gives the
  // finest rotation: an error e in arg c_k turns the estimate by e / k, and e
  // shrinks as |c_k| grows.
  m.orientation_order = 0;
  int strongest = 0;
  double finest = 0;
  for (int k = 2; k <= kMaxOrder; ++k) {
    if (strength[k] >= kMinOrderStrength && k <= kMaxPreferredOrder && k * strength[k] > finest) {
      m.orientation_order = k;
      finest = k * strength[k];
    }
    if (strength[k] > strength[strongest]) strongest = k;
  }
  for (int k = kMaxPreferredOrder + 1; k <= kMaxOrder && m.orientation_order == 0; ++k) {
    if (strength[k] >= kMinOrderStrength) m.orientation_order = k;
  }
  if (m.orientation_order == 0 && strongest >= 2 && strength[strongest] >= kWeakOrderStrength) {
    m.orientation_order = strongest;
  }
  m.orientation_phase_deg = m.orientation_order > 0 ? phase[m.orientation_order] : 0;
}

// The symmetry order of a model trained on region `r` and whether it equals
// its mirror image.
void setSymmetries(PartModel& m, const Region& r) {
  // Symmetries, by verifying the model against its own training edges.
  const int margin = static_cast<int>(std::ceil(m.edge_tolerance)) + 4;
  const cv::Rect roi = cv::Rect(r.bbox.x - margin, r.bbox.y - margin, r.bbox.width + 2 * margin,
                                r.bbox.height + 2 * margin);
  const EdgeDistance edges(contoursOf(r), roi);
  m.symmetry_order = 1;
  int passed = 0;
  for (int s = 2; s <= kMaxOrder; ++s) {
    if (verifyScore(m.samples, r.centroid, 360.0 / s, edges, m.edge_tolerance) >= kSymmetryScore) {
      m.symmetry_order = s;
      ++passed;
    }
  }
  if (m.orientation_order == 0 && passed == kMaxOrder - 1) m.symmetry_order = 0;
  if (m.orientation_order == 0) {
    m.body.mirror_symmetric = true;
  } else {
    // The mirror image lines up with the part at one of the turns where its
    // complex moment does (as in recognition); a hair either side absorbs
    // the phase's pixel noise.
    const int k = m.orientation_order;
    double least = std::numeric_limits<double>::infinity();
    for (int j = 0; j < k; ++j) {
      for (double nudge : {-0.5, -0.25, 0.0, 0.25, 0.5}) {
        least = std::min(least,
                         chiralLength(m, 2 * m.orientation_phase_deg / k + j * 360.0 / k + nudge));
      }
    }
    m.body.mirror_symmetric = least < kMinChiralLength;
  }
}

// Which Hu invariants of a model trained on region `r` of `grey` it uses,
// and their tolerance.
void setHuTolerance(PartModel& m, const cv::Mat& grey, const Region& r,
                    const TrainOptions& options) {
  // Which Hu invariants survive turning, and how far they move.
  const HuArray& h0 = m.body.log_hu;
  std::array<double, 7> spread{};
  std::array<bool, 7> same_sign;
  same_sign.fill(true);
  std::vector<HuArray> probes;
  for (double deg : kProbeTurnsDeg) {
    HuArray h;
    if (!turnedLogHu(grey, r, deg, options, &h)) continue;
    probes.push_back(h);
    for (size_t i = 0; i < h.size(); ++i) {
      spread[i] = std::max(spread[i], std::abs(h[i] - h0[i]));
      same_sign[i] = same_sign[i] && (h[i] >= 0) == (h0[i] >= 0);
    }
  }
  for (size_t i = 0; i < h0.size(); ++i) {
    m.body.hu_used[i] = !probes.empty() && same_sign[i] && spread[i] <= kMaxHuSpread &&
                        std::abs(h0[i]) <= kMaxLogHu;
  }
  double worst = 0;
  for (const auto& h : probes) worst = std::max(worst, huDistance(m.body, h));
  m.body.hu_tolerance = std::max(kMinHuTolerance, 3 * worst);
}

}  // namespace

void prepareModel(PartModel& model) {
  model.samples = sampleBoundary(model.loops, 1.0);
  model.radius = 0;
  for (const auto& s : model.samples)
    model.radius = std::max(model.radius, std::hypot(s.point.x, s.point.y));
  // Farther than twice the tolerance, every distance weighs the same
  // (handednessWeight).
  model.boundary_map =
      std::make_shared<const BoundaryDistanceMap>(model.loops, 2 * model.edge_tolerance + 1.0);
  model.blob_search = makeBlobSearchModel(model);
}

Result<PartModel> trainModel(const cv::Mat& grey, int type, const std::string& name,
                             const TrainOptions& options) {
  if (grey.empty() || grey.type() != CV_8UC1) {
    return makeError(PartModelErrc::kNotGrey, "the training image must be 8-bit grey");
  }
  const auto regions = findRegions(binarize(grey, options.binarize), options.regions, grey);
  if (regions.empty()) return makeError(PartModelErrc::kNoPart, "no part in the image");
  if (regions.size() > 1) {
    return makeError(
        PartModelErrc::kSeveralParts,
        std::to_string(regions.size()) + " parts in the image, training needs exactly one");
  }
  return trainModelFromRegion(grey, regions.front(), type, name, options);
}

void moveBoundary(PartModel& m, double turn_deg, cv::Point2d shift) {
  const double c = std::cos(turn_deg * kRadPerDeg);
  const double s = std::sin(turn_deg * kRadPerDeg);
  const auto move = [&](cv::Point2d p) {
    return cv::Point2d(c * p.x - s * p.y, s * p.x + c * p.y) + shift;
  };
  for (auto& loop : m.loops) {
    for (auto& p : loop.primitives) {
      p.start = move(p.start);
      p.end = move(p.end);
      p.centre = move(p.centre);
    }
  }
  m.corners = findCorners(m.loops, m.conformity);
  prepareModel(m);
}

cv::Point2d referencePoint(const PartModel& model, const Region& r, const ImagePose& pose) {
  if (!r.uneven_light) return r.centroid;
  const auto outline = outlineCentroid(model, r, pose);
  if (!outline || cv::norm(*outline - r.centroid) > kMaxOutlineShiftPx) return r.centroid;
  return *outline;
}

void addViewReading(PartModel& m, cv::Point2d reading) {
  m.views.push_back(reading);
  const cv::Point2d origin = originFromViews(m.views);
  // Boundary points are held about the current origin: about the new one
  // they lie (new - old) the other way.
  moveBoundary(m, 0.0, m.origin_shift - origin);
  m.origin_shift = origin;
}

Result<PartModel> trainModelFromRegion(const cv::Mat& grey, const Region& r, int type,
                                       const std::string& name, const TrainOptions& options) {
  if (grey.empty() || grey.type() != CV_8UC1) {
    return makeError(PartModelErrc::kNotGrey, "the training image must be 8-bit grey");
  }
  PartModel m;
  m.type = type;
  m.name = name;
  m.trained_centroid = r.centroid;
  m.trained_angle_deg = r.angle_deg;
  m.min_region_area = options.regions.min_area;
  m.min_hole_area = options.regions.min_hole_area;
  m.conformity = options.conformity;
  m.verify_percent = options.verify_percent;
  m.edge_tolerance = options.conformity + 1.0;
  m.body.area = r.area;
  m.body.area_tolerance = options.area_tolerance;
  m.body.holes = r.holes;
  m.body.log_hu = logHu(huInvariants(r.moments));

  // Boundary in the model frame: the trained pose, centroid at the origin.
  std::vector<std::vector<cv::Point2d>> contours;
  for (const auto& c : contoursOf(r)) {
    std::vector<cv::Point2d> loop;
    loop.reserve(c.size());
    for (const auto& p : c) loop.emplace_back(p.x - r.centroid.x, p.y - r.centroid.y);
    contours.push_back(std::move(loop));
  }
  m.loops = fitLoops(contours, m.conformity);
  snapToEdges(m.loops, r, r.centroid);
  m.corners = findCorners(m.loops, m.conformity);
  prepareModel(m);
  centreOnEdges(m, r);
  weighByContrast(m, grey, r.centroid);

  setOrientation(m, r);
  setSymmetries(m, r);
  setHuTolerance(m, grey, r, options);
  // The origin where the part's edges put its centroid, under uneven
  // light (referencePoint); the boundary moved the other way, so that the
  // fit on the teach image's edges lands on it.
  const cv::Point2d origin = referencePoint(m, r, {r.centroid, 0.0, false});
  if (origin != r.centroid) {
    moveBoundary(m, 0.0, r.centroid - origin);
    m.trained_centroid = origin;
  }
  // Where the teach image's edges lie beyond the lines and arcs: a part a
  // fifth of whose outline another hides is then fitted to what shows as
  // the whole was. Front-light benchmark, overlapping pairs of 14 unseen
  // types, 4 scenes, position RMS px without and with them: clean 0.0525 /
  // 0.0151, textured 0.051 / 0.020, 30 grey levels 0.075 / 0.060; touching
  // 0.0138 / 0.0119; separated alike. Separated parts, 15 % of each
  // outline left out of the fit without them: 0.010 -> 0.040 px.
  // A part with rotational symmetry is found at any of its turns: its
  // offsets are the mean over them, read about the origin (the part's
  // centre of symmetry, as its edges put it). The fit then places the part
  // by its symmetry, not by where one teach image read its centroid: four
  // symmetric shapes (2 to 12 turns), 24 scenes, separated / overlapping,
  // RMS against the drawn centre, without and with: clean 0.0167 / 0.0198
  // and 0.0080 / 0.0096, textured 0.0225 / 0.0229 and 0.0108 / 0.0123,
  // glossy 0.037 / 0.037 and 0.017 / 0.019, wood 0.025 / 0.029 and 0.017 /
  // 0.021, 30 grey levels 0.049 / 0.057 and 0.037 / 0.048 (read about the
  // region's centroid instead, worse than none on glossy and at 30
  // levels). A disc (any turn) keeps its circle alone.
  if (m.symmetry_order >= 1) {
    measureEdgeOffsets(m.loops, r, m.trained_centroid, m.symmetry_order);
    prepareModel(m);
  }
  return m;
}

PartModel scaledModel(const PartModel& model, double scale) {
  PartModel m = model;
  const double area = scale * scale;
  m.body.area *= area;
  m.min_region_area *= area;
  m.min_hole_area *= area;
  for (auto& loop : m.loops) {
    for (auto& p : loop.primitives) {
      const Primitive taught = p;
      p.start *= scale;
      p.end *= scale;
      p.centre *= scale;
      p.radius *= scale;
      // The offsets and weights again at the scaled length's points (the
      // offsets scaled).
      const int count = edgeOffsetCount(p.length());
      if (!taught.edge_weights_pct.empty()) {
        p.edge_weights_pct.resize(static_cast<size_t>(count));
        for (int k = 0; k < count; ++k) {
          p.edge_weights_pct[static_cast<size_t>(k)] =
              static_cast<uint8_t>(taught.weightPctAt((k + 0.5) / count));
        }
      }
      if (taught.edge_offsets_mpx.empty()) continue;
      p.edge_offsets_mpx.resize(static_cast<size_t>(count));
      for (int k = 0; k < count; ++k) {
        p.edge_offsets_mpx[static_cast<size_t>(k)] =
            edgeOffsetMpx(scale * taught.edgeOffsetAt((k + 0.5) / count));
      }
    }
  }
  const auto scaled = [scale](Range r) { return Range{r.min * scale, r.max * scale}; };
  for (auto& c : m.corners) {
    c.at *= scale;
    c.length_in = scaled(c.length_in);
    c.length_out = scaled(c.length_out);
    c.radius_in = scaled(c.radius_in);
    c.radius_out = scaled(c.radius_out);
  }
  prepareModel(m);
  return m;
}

}  // namespace picksight::vision
