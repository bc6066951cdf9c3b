// Disc and dot-grid targets measured on their sub-pixel edges.
#include "picksight/calibration/target_measurement.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "picksight/calibration/calibration_errors.hpp"
#include "picksight/common/angles.hpp"

namespace picksight::calibration {
namespace {
constexpr int kRounds = 4;
constexpr double kStepPx = 0.2;  // sampling step along a ray

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// Bilinear grey level at (x, y) of a float image (pixel centres at integer
// coordinates); NaN outside.
double sample(const cv::Mat& img, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= img.cols || y0 + 1 >= img.rows)
    return std::numeric_limits<double>::quiet_NaN();
  const double fx = x - x0, fy = y - y0;
  const float* r0 = img.ptr<float>(y0);
  const float* r1 = img.ptr<float>(y0 + 1);
  return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) +
         fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

// An ellipse as centre and quadratic form: (p - c)^T Q (p - c) = 1.
struct Ellipse {
  cv::Point2d c;
  cv::Matx22d q;
  // Distance from the centre to the ellipse along unit direction d.
  double reach(cv::Point2d d) const {
    return 1.0 / std::sqrt(q(0, 0) * d.x * d.x + 2 * q(0, 1) * d.x * d.y + q(1, 1) * d.y * d.y);
  }
};

// Algebraic fit of A x^2 + B xy + C y^2 + D x + E y = 1 to points taken
// relative to `origin` (which must lie inside the ellipse).
std::optional<Ellipse> fitConic(const std::vector<cv::Point2d>& pts, cv::Point2d origin,
                                double scale) {
  if (pts.size() < 6) return std::nullopt;
  cv::Mat a(static_cast<int>(pts.size()), 5, CV_64F), b(static_cast<int>(pts.size()), 1, CV_64F);
  for (size_t i = 0; i < pts.size(); ++i) {
    const double x = (pts[i].x - origin.x) / scale, y = (pts[i].y - origin.y) / scale;
    double* row = a.ptr<double>(static_cast<int>(i));
    row[0] = x * x;
    row[1] = x * y;
    row[2] = y * y;
    row[3] = x;
    row[4] = y;
    b.at<double>(static_cast<int>(i)) = 1.0;
  }
  cv::Mat p;
  if (!cv::solve(a, b, p, cv::DECOMP_SVD)) return std::nullopt;
  const double A = p.at<double>(0), B = p.at<double>(1), C = p.at<double>(2), D = p.at<double>(3),
               E = p.at<double>(4);
  const double det = 4 * A * C - B * B;
  if (!(det > 0)) return std::nullopt;
  const double cx = (B * E - 2 * C * D) / det, cy = (B * D - 2 * A * E) / det;
  // Value of the conic (minus 1) at the centre: the form is then
  // u^T S u = -f0 for u = p - centre.
  const double f0 = A * cx * cx + B * cx * cy + C * cy * cy + D * cx + E * cy - 1.0;
  if (!(f0 < 0)) return std::nullopt;
  Ellipse e;
  e.c = origin + cv::Point2d(cx, cy) * scale;
  const double k = -1.0 / (f0 * scale * scale);
  e.q = cv::Matx22d(A * k, B / 2 * k, B / 2 * k, C * k);
  return e;
}

struct RayEdge {
  cv::Point2d point;
  double contrast = 0;  // step height seen on the ray
};

// The edge along the ray from e.c in direction d, searched within `w` of the
// current ellipse: the centroid of the gradient, each sample weighted by
// sqrt(r / reach). Blur moves a curved edge's gradient peak inward by
// sigma^2 / (2 R) (a blurred disc's radial gradient falls as 1/sqrt(r)
// across the edge); the weight cancels that to first order.
//
// Until the edge's width `edge_var` (px^2) is known only positive gradients
// count (a wide first search, where the noise of the whole window would
// otherwise pull); later, narrow searches keep the noise's negative half
// too, so that it averages out instead of adding a positive mass the
// curvature weight would pull outwards. The ray's
// gradient profile, baseline removed, is added to `profile_sum`.
std::optional<RayEdge> edgeOnRay(const cv::Mat& img, const Ellipse& e, cv::Point2d d, double w,
                                 double polarity, double edge_var,
                                 std::vector<double>& profile_sum) {
  const double reach = e.reach(d);
  const bool clamp = edge_var <= 0;
  // Later rounds weight the samples by a Gaussian window 1.5 edge widths
  // wide about the expected edge: the noise far from the edge, which only
  // adds scatter, then counts little.
  const double window_sigma = clamp ? 0.0 : 1.5 * std::sqrt(edge_var);
  const double window_pull = clamp ? 0.0 : edge_var / (edge_var + window_sigma * window_sigma);
  const int n = static_cast<int>(profile_sum.size());
  const double start = reach - w;
  if (start <= kStepPx) return std::nullopt;
  std::vector<double> profile(static_cast<size_t>(n + 2));
  for (int j = -1; j <= n; ++j) {
    const double r = start + j * kStepPx;
    const double v = sample(img, e.c.x + d.x * r, e.c.y + d.y * r);
    if (std::isnan(v)) return std::nullopt;
    profile[static_cast<size_t>(j + 1)] = v;
  }
  std::vector<double> g(static_cast<size_t>(n));
  for (int j = 0; j < n; ++j) {
    g[static_cast<size_t>(j)] =
        polarity * (profile[static_cast<size_t>(j)] - profile[static_cast<size_t>(j + 2)]) /
        (2 * kStepPx);
  }
  // A sloping illumination adds a constant to the gradient: remove the line
  // through the two ends' mean levels.
  const int tail = std::max(1, n / 10);
  double in = 0, out = 0;
  for (int j = 0; j < tail; ++j) {
    in += g[static_cast<size_t>(j)];
    out += g[static_cast<size_t>(n - 1 - j)];
  }
  in /= tail;
  out /= tail;
  double sw = 0, swr = 0, contrast = 0;
  for (int j = 0; j < n; ++j) {
    const double t = static_cast<double>(j) / (n - 1);
    const double v = g[static_cast<size_t>(j)] - (in + (out - in) * t);
    profile_sum[static_cast<size_t>(j)] += v;
    if (clamp && v <= 0) continue;
    const double r = start + j * kStepPx;
    double wt = v * std::sqrt(r / reach);
    if (window_sigma > 0) wt *= std::exp(-0.5 * std::pow((r - reach) / window_sigma, 2));
    sw += wt;
    swr += wt * r;
    contrast += v * kStepPx;
  }
  if (!(sw > 0) || !(contrast > 0)) return std::nullopt;
  double re = swr / sw;
  // A Gaussian window of variance s^2 centred on `reach` pulls a Gaussian
  // edge of variance e^2 towards it by e^2 / (e^2 + s^2) of the distance:
  // undo the pull (window_pull is that fraction).
  if (window_sigma > 0) re = reach + (re - reach) / (1 - window_pull);
  if (std::abs(re - reach) > 0.8 * w) return std::nullopt;
  return RayEdge{e.c + d * re, contrast};
}
// Variance (px^2) of a gradient profile sampled kStepPx apart about its centroid.
double profileSpread2(const std::vector<double>& profile) {
  double sw = 0, swr = 0, swr2 = 0;
  for (size_t j = 0; j < profile.size(); ++j) {
    const double v = std::max(0.0, profile[j]);
    const double r = static_cast<double>(j) * kStepPx;
    sw += v;
    swr += v * r;
    swr2 += v * r * r;
  }
  if (!(sw > 0)) return 0;
  const double mean = swr / sw;
  return std::max(0.0, swr2 / sw - mean * mean);
}
// Polarity of the disc about `centre` (+1 bright, -1 dark): a bright disc
// has its gradient pointing inwards.
double discPolarity(const cv::Mat& img, cv::Point2d centre, double radius_guess, double w0) {
  double inside = 0, outside = 0;
  for (int k = 0; k < 16; ++k) {
    const double a = 2 * M_PI * k / 16;
    const cv::Point2d d(std::cos(a), std::sin(a));
    const double vi =
        sample(img, centre.x + d.x * (radius_guess - w0), centre.y + d.y * (radius_guess - w0));
    const double vo =
        sample(img, centre.x + d.x * (radius_guess + w0), centre.y + d.y * (radius_guess + w0));
    if (!std::isnan(vi)) inside += vi;
    if (!std::isnan(vo)) outside += vo;
  }
  return inside >= outside ? 1.0 : -1.0;
}

// The points within four robust deviations (at least 0.05 px) of `fit`.
std::vector<cv::Point2d> closeToEllipse(const std::vector<cv::Point2d>& pts, const Ellipse& fit) {
  std::vector<double> dist;
  for (const auto& p : pts) {
    const cv::Point2d u = p - fit.c;
    const double len = cv::norm(u);
    dist.push_back(len - fit.reach(u / len));
  }
  std::vector<double> abs_dist;
  for (double d : dist) abs_dist.push_back(std::abs(d));
  const double cut = std::max(0.05, 4 * 1.4826 * median(abs_dist));
  std::vector<cv::Point2d> kept;
  for (size_t i = 0; i < pts.size(); ++i) {
    if (std::abs(dist[i]) <= cut) kept.push_back(pts[i]);
  }
  return kept;
}

// The centre (image pixels: `offset` added), radii along X and Y, semi-axes
// and major axis of the fitted ellipse `e`.
void setAxes(const Ellipse& e, cv::Point2d offset, DiscMeasurement& m) {
  const cv::Matx22d inv = e.q.inv();
  m.centre = e.c + offset;
  m.radius_x = std::sqrt(inv(0, 0));
  m.radius_y = std::sqrt(inv(1, 1));
  // Semi-axes from the eigenvalues of the form.
  const double tr = e.q(0, 0) + e.q(1, 1);
  const double disc = std::sqrt(std::pow(e.q(0, 0) - e.q(1, 1), 2) + 4 * e.q(0, 1) * e.q(0, 1));
  m.major = 1.0 / std::sqrt((tr - disc) / 2);
  m.minor = 1.0 / std::sqrt((tr + disc) / 2);
  // The major axis is the eigenvector of the smaller eigenvalue.
  m.axis_deg = 0.5 * std::atan2(-2 * e.q(0, 1), e.q(1, 1) - e.q(0, 0)) * kDegPerRad;
}
}  // namespace

Result<DiscMeasurement> measureDisc(const cv::Mat& grey, cv::Point2d centre_guess,
                                    double radius_guess) {
  if (grey.empty() || grey.channels() != 1)
    return makeError(CalibrationErrc::kBadInput, "the target image must be one grey channel");
  if (!(radius_guess >= 2) || !std::isfinite(centre_guess.x) || !std::isfinite(centre_guess.y))
    return makeError(CalibrationErrc::kBadTarget, "the target is too small to measure (radius " +
                                                      std::to_string(radius_guess) + " px)");
  // Work on a float copy of the target's surroundings only.
  const double margin = radius_guess * 1.6 + 24;
  const cv::Rect box = cv::Rect(cv::Point(static_cast<int>(centre_guess.x - margin),
                                          static_cast<int>(centre_guess.y - margin)),
                                cv::Point(static_cast<int>(centre_guess.x + margin) + 1,
                                          static_cast<int>(centre_guess.y + margin) + 1)) &
                       cv::Rect(0, 0, grey.cols, grey.rows);
  if (box.width < 8 || box.height < 8)
    return makeError(CalibrationErrc::kBadTarget, "the target lies outside the image");
  cv::Mat img;
  grey(box).convertTo(img, CV_32F);
  const cv::Point2d offset(box.x, box.y);

  Ellipse e{centre_guess - offset, cv::Matx22d(1, 0, 0, 1) * (1.0 / (radius_guess * radius_guess))};
  const double w0 = std::clamp(0.35 * radius_guess, 2.0, 15.0);
  double w = w0;
  const double polarity = discPolarity(img, e.c, radius_guess, w0);

  DiscMeasurement m;
  double edge_var = 0;  // of the mean gradient profile, once known
  for (int round = 0; round < kRounds; ++round) {
    const double r_mean = 1.0 / std::sqrt(std::sqrt(e.q(0, 0) * e.q(1, 1) - e.q(0, 1) * e.q(0, 1)));
    const int rays = std::clamp(static_cast<int>(4 * M_PI * r_mean), 90, 4096);
    std::vector<RayEdge> edges;
    edges.reserve(static_cast<size_t>(rays));
    std::vector<double> profile_sum(static_cast<size_t>(std::ceil(2 * w / kStepPx)) + 1, 0.0);
    for (int k = 0; k < rays; ++k) {
      const double a = 2 * M_PI * (k + 0.5) / rays;
      if (auto edge =
              edgeOnRay(img, e, {std::cos(a), std::sin(a)}, w, polarity, edge_var, profile_sum))
        edges.push_back(*edge);
    }
    if (static_cast<int>(edges.size()) < rays / 2)
      return makeError(CalibrationErrc::kBadTarget, "the target's edge is not clear all round (" +
                                                        std::to_string(edges.size()) + " of " +
                                                        std::to_string(rays) + " rays found it)");
    // Rays across dust or a shadow see a weaker step: leave them out.
    std::vector<double> contrasts;
    for (const auto& edge : edges) contrasts.push_back(edge.contrast);
    const double typical = median(contrasts);
    std::vector<cv::Point2d> pts;
    for (const auto& edge : edges) {
      if (edge.contrast < 0.5 * typical) continue;
      pts.push_back(edge.point);
    }
    auto fit = fitConic(pts, e.c, r_mean);
    if (!fit) return makeError(CalibrationErrc::kBadTarget, "the target's edge is not an ellipse");
    // Points far off the first fit (a nick, a speck on the edge) go; refit.
    const std::vector<cv::Point2d> kept = closeToEllipse(pts, *fit);
    fit = fitConic(kept, e.c, r_mean);
    if (!fit) return makeError(CalibrationErrc::kBadTarget, "the target's edge is not an ellipse");
    e = *fit;
    double ss = 0;
    for (const auto& p : kept) {
      const cv::Point2d u = p - e.c;
      const double len = cv::norm(u);
      const double d = len - e.reach(u / len);
      ss += d * d;
    }
    m.edge_points = static_cast<int>(kept.size());
    m.edge_rms = std::sqrt(ss / static_cast<double>(kept.size()));
    // The spread of the mean gradient profile (the noise averages out over
    // the rays) includes the pixel's box (1/12 px^2) and the bilinear
    // sampling's triangle (1/6) besides the blur.
    const double spread2 = profileSpread2(profile_sum);
    edge_var = spread2;
    m.edge_width = std::sqrt(std::max(0.0, spread2 - 0.25));
    // Later rounds search only where the edge's gradient is.
    w = std::clamp(4.0 * std::sqrt(spread2) + 1.0, 1.5, w0);
  }
  setAxes(e, offset, m);
  return m;
}

Result<PixelScale> scaleFromDisc(const DiscMeasurement& disc, double radius_mm) {
  if (!(radius_mm > 0) || !std::isfinite(radius_mm))
    return makeError(CalibrationErrc::kBadInput, "target radius must be positive");
  if (!(disc.radius_x > 0) || !(disc.radius_y > 0))
    return makeError(CalibrationErrc::kBadTarget, "target has no size");
  PixelScale s;
  s.mm_per_px_x = radius_mm / disc.radius_x;
  s.mm_per_px_y = radius_mm / disc.radius_y;
  // The axis is meaningless for a circle: it counts once the ellipse is
  // measurably elongated.
  if (disc.major - disc.minor > 1e-3 * disc.major)
    s.skew_deg = picksight::angleDiffDeg(disc.axis_deg, 0.0, 90.0);
  return s;
}

namespace {
// The dots' centres: the minority class of an Otsu threshold, its regions
// clear of the border and of about the typical area, each measured as a
// disc.
Result<std::vector<cv::Point2d>> dotCentres(const cv::Mat& grey) {
  cv::Mat grey8 = grey;
  if (grey.depth() != CV_8U) cv::normalize(grey, grey8, 0, 255, cv::NORM_MINMAX, CV_8U);
  cv::Mat binary;
  cv::threshold(grey8, binary, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
  // The dots are the minority class.
  if (static_cast<size_t>(cv::countNonZero(binary)) > binary.total() / 2)
    cv::bitwise_not(binary, binary);
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(binary, labels, stats, centroids, 8);
  std::vector<int> candidates;
  std::vector<double> areas;
  for (int i = 1; i < n; ++i) {
    const int x = stats.at<int>(i, cv::CC_STAT_LEFT), y = stats.at<int>(i, cv::CC_STAT_TOP);
    const int w = stats.at<int>(i, cv::CC_STAT_WIDTH), h = stats.at<int>(i, cv::CC_STAT_HEIGHT);
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    if (x == 0 || y == 0 || x + w >= grey.cols || y + h >= grey.rows || area < 12) continue;
    candidates.push_back(i);
    areas.push_back(area);
  }
  const double typical = median(areas);
  std::vector<cv::Point2d> centres;
  for (int i : candidates) {
    const double area = stats.at<int>(i, cv::CC_STAT_AREA);
    if (area < 0.5 * typical || area > 2 * typical) continue;
    auto dot = measureDisc(grey, {centroids.at<double>(i, 0), centroids.at<double>(i, 1)},
                           std::sqrt(area / M_PI));
    if (!dot) return dot.error();
    centres.push_back(dot->centre);
  }
  return centres;
}

// The dot nearest the dots' mean.
cv::Point2d dotNearestMiddle(const std::vector<cv::Point2d>& centres) {
  cv::Point2d mean(0, 0);
  for (const auto& c : centres) mean += c;
  mean *= 1.0 / static_cast<double>(centres.size());
  const auto nearest = [&](cv::Point2d to) {
    return *std::min_element(centres.begin(), centres.end(), [&](cv::Point2d a, cv::Point2d b) {
      return cv::norm(a - to) < cv::norm(b - to);
    });
  };
  return nearest(mean);
}

// The grid's two steps from `p0`: its nearest neighbour, then the nearest
// dot off that line; the one nearer the X axis first.
Result<std::pair<cv::Point2d, cv::Point2d>> gridSteps(const std::vector<cv::Point2d>& centres,
                                                      cv::Point2d p0) {
  cv::Point2d u(0, 0), v(0, 0);
  for (const auto& c : centres) {
    const cv::Point2d d = c - p0;
    if (cv::norm(d) > 1e-9 && (u == cv::Point2d(0, 0) || cv::norm(d) < cv::norm(u))) u = d;
  }
  for (const auto& c : centres) {
    const cv::Point2d d = c - p0;
    const double len = cv::norm(d);
    if (len < 1e-9 || std::abs(u.cross(d)) < 0.5 * cv::norm(u) * len) continue;
    if (v == cv::Point2d(0, 0) || len < cv::norm(v)) v = d;
  }
  if (v == cv::Point2d(0, 0))
    return makeError(CalibrationErrc::kBadTarget, "the dots are not a grid (all on one line)");
  if (std::abs(u.x) < std::abs(u.y)) std::swap(u, v);
  return std::make_pair(u, v);
}
}  // namespace

Result<DotGridMeasurement> measureDotGrid(const cv::Mat& grey, double pitch_mm) {
  if (!(pitch_mm > 0) || !std::isfinite(pitch_mm))
    return makeError(CalibrationErrc::kBadInput, "the grid pitch must be positive");
  if (grey.empty() || grey.channels() != 1)
    return makeError(CalibrationErrc::kBadInput, "the target image must be one grey channel");
  auto found = dotCentres(grey);
  if (!found) return found.error();
  std::vector<cv::Point2d> centres = std::move(*found);
  if (centres.size() < 4)
    return makeError(CalibrationErrc::kBadTarget, "a dot grid needs at least 2 x 2 dots; found " +
                                                      std::to_string(centres.size()));
  // The grid's two steps from the dot nearest the middle.
  const cv::Point2d p0 = dotNearestMiddle(centres);
  const auto steps = gridSteps(centres, p0);
  if (!steps) return steps.error();
  const auto [u, v] = *steps;
  const cv::Matx22d to_index = cv::Matx22d(u.x, v.x, u.y, v.y).inv();
  // Grid indices of every dot, then the grid fitted to all of them.
  cv::Mat a(static_cast<int>(centres.size()), 3, CV_64F);
  cv::Mat bx(static_cast<int>(centres.size()), 1, CV_64F), by = bx.clone();
  int min_i = 0, max_i = 0, min_j = 0, max_j = 0;
  std::vector<std::pair<int, int>> seen;
  std::vector<cv::Point2i> indices;
  for (size_t k = 0; k < centres.size(); ++k) {
    const cv::Vec2d f = to_index * cv::Vec2d(centres[k].x - p0.x, centres[k].y - p0.y);
    const int i = static_cast<int>(std::lround(f[0])), j = static_cast<int>(std::lround(f[1]));
    if (std::abs(f[0] - i) > 0.25 || std::abs(f[1] - j) > 0.25)
      return makeError(CalibrationErrc::kBadTarget, "the dots are not on a regular grid");
    seen.emplace_back(i, j);
    indices.emplace_back(i, j);
    min_i = std::min(min_i, i);
    max_i = std::max(max_i, i);
    min_j = std::min(min_j, j);
    max_j = std::max(max_j, j);
    const int row = static_cast<int>(k);
    a.at<double>(row, 0) = 1;
    a.at<double>(row, 1) = i;
    a.at<double>(row, 2) = j;
    bx.at<double>(row) = centres[k].x;
    by.at<double>(row) = centres[k].y;
  }
  std::sort(seen.begin(), seen.end());
  if (std::adjacent_find(seen.begin(), seen.end()) != seen.end())
    return makeError(CalibrationErrc::kBadTarget, "two dots fall on one grid position");
  cv::Mat px, py;
  cv::solve(a, bx, px, cv::DECOMP_SVD);
  cv::solve(a, by, py, cv::DECOMP_SVD);
  const cv::Point2d step_u(px.at<double>(1), py.at<double>(1));
  const cv::Point2d step_v(px.at<double>(2), py.at<double>(2));
  double ss = 0;
  for (size_t k = 0; k < centres.size(); ++k) {
    const cv::Mat row = a.row(static_cast<int>(k));
    const cv::Point2d fit(row.dot(px.t()), row.dot(py.t()));
    ss += std::pow(cv::norm(fit - centres[k]), 2);
  }
  DotGridMeasurement g;
  // Pixels per millimetre B = [u v] / pitch = diag(1/sx, 1/sy) R, so
  // B B^T = diag(1/sx^2, 1/sy^2) whatever the grid's rotation R.
  const double bxx = (step_u.x * step_u.x + step_v.x * step_v.x) / (pitch_mm * pitch_mm);
  const double byy = (step_u.y * step_u.y + step_v.y * step_v.y) / (pitch_mm * pitch_mm);
  g.scale.mm_per_px_x = 1.0 / std::sqrt(bxx);
  g.scale.mm_per_px_y = 1.0 / std::sqrt(byy);
  // A grid imaged with its steps off square: tilt or skew.
  const double between =
      std::acos(std::clamp(step_u.dot(step_v) / (cv::norm(step_u) * cv::norm(step_v)), -1.0, 1.0)) *
      kDegPerRad;
  g.scale.skew_deg = std::abs(90.0 - between);
  g.dots = static_cast<int>(centres.size());
  g.cols = max_i - min_i + 1;
  g.rows = max_j - min_j + 1;
  g.grid_rms_px = std::sqrt(ss / static_cast<double>(centres.size()));
  g.rotation_deg = std::atan2(step_u.y, step_u.x) * kDegPerRad;
  g.centres = std::move(centres);
  g.indices = std::move(indices);
  return g;
}

}  // namespace picksight::calibration
