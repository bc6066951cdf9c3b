// Robot-camera calibration: least-squares (Kabsch in 2D) and geometric
// (circle intersections) estimators behind least median of
// squares outlier rejection.
#include "picksight/calibration/robot_camera.hpp"

#include "picksight/common/angles.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace picksight::calibration {

const char* errorName(CalibrationErrc e) {
  switch (e) {
    case CalibrationErrc::kTooFewPoints:
      return "too few points";
    case CalibrationErrc::kDegeneratePoints:
      return "degenerate points";
    case CalibrationErrc::kBadTarget:
      return "bad target";
    case CalibrationErrc::kBadInput:
      return "bad input";
    case CalibrationErrc::kBadFile:
      return "bad file";
  }
  return "unknown";
}
namespace {
using picksight::kDegPerRad;
using picksight::signedDeg;
// Points closer together than this (mm) along their spread's minor axis are
// taken as lying on one line: rotation and handedness are then unobservable.
constexpr double kMinSpreadMm = 1.0;

cv::Point2d mirror(cv::Point2d p, bool mirrored) { return mirrored ? cv::Point2d(p.x, -p.y) : p; }

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

std::vector<double> squaredResiduals(const RigidTransform& t, const std::vector<PointPair>& pts) {
  std::vector<double> r;
  r.reserve(pts.size());
  for (const auto& p : pts) {
    const cv::Point2d d = t.apply(p.vision) - p.robot;
    r.push_back(d.dot(d));
  }
  return r;
}

// Least squares over the points flagged in `use` (2D Kabsch).
RigidTransform leastSquares(const std::vector<PointPair>& pts, const std::vector<bool>& use,
                            bool mirrored) {
  cv::Point2d cv_sum(0, 0), cr_sum(0, 0);
  int n = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    if (!use[i]) continue;
    cv_sum += mirror(pts[i].vision, mirrored);
    cr_sum += pts[i].robot;
    ++n;
  }
  const cv::Point2d cv_mean = cv_sum / n;
  const cv::Point2d cr_mean = cr_sum / n;
  double sxx = 0, sxy = 0, syx = 0, syy = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    if (!use[i]) continue;
    const cv::Point2d a = mirror(pts[i].vision, mirrored) - cv_mean;
    const cv::Point2d b = pts[i].robot - cr_mean;
    sxx += a.x * b.x;
    sxy += a.x * b.y;
    syx += a.y * b.x;
    syy += a.y * b.y;
  }
  const double theta = std::atan2(sxy - syx, sxx + syy);
  RigidTransform t;
  t.mirrored = mirrored;
  t.rz_deg = signedDeg(theta * kDegPerRad);
  const double c = std::cos(theta), s = std::sin(theta);
  t.dx = cr_mean.x - (c * cv_mean.x - s * cv_mean.y);
  t.dy = cr_mean.y - (s * cv_mean.x + c * cv_mean.y);
  return t;
}

// The paper's geometric method. A rigid motion keeps distances, so the
// vision origin, seen in the robot frame, lies at distance |v_i| from every
// robot point r_i: on a circle around each. Pairs of circles intersect in
// two candidates; the right ones cluster at the origin. The rotation then
// follows from each point's bearing from that origin in both frames (the
// law of cosines in the paper; bearings here).
RigidTransform geometric(const std::vector<PointPair>& pts, const std::vector<bool>& use,
                         bool mirrored, double cluster_radius) {
  std::vector<cv::Point2d> candidates;
  std::vector<std::pair<cv::Point2d, cv::Point2d>> pairs;
  for (size_t i = 0; i < pts.size(); ++i) {
    for (size_t j = i + 1; j < pts.size(); ++j) {
      if (!use[i] || !use[j]) continue;
      const cv::Point2d ci = pts[i].robot, cj = pts[j].robot;
      const double ri = cv::norm(pts[i].vision), rj = cv::norm(pts[j].vision);
      const cv::Point2d d = cj - ci;
      const double dist = cv::norm(d);
      if (dist < 1e-9) continue;
      // Distance from ci along d to the chord; with noise the circles may
      // miss each other: then the closest point on the line of centres.
      const double a = (ri * ri - rj * rj + dist * dist) / (2 * dist);
      const double h2 = ri * ri - a * a;
      const double h = h2 > 0 ? std::sqrt(h2) : 0;
      const cv::Point2d base = ci + d * (a / dist);
      const cv::Point2d perp(-d.y / dist, d.x / dist);
      pairs.emplace_back(base + perp * h, base - perp * h);
      candidates.push_back(base + perp * h);
      candidates.push_back(base - perp * h);
    }
  }
  // The candidate with the most neighbours seeds the cluster.
  cv::Point2d seed(0, 0);
  int best = -1;
  for (const auto& c : candidates) {
    int count = 0;
    for (const auto& o : candidates) count += cv::norm(o - c) < cluster_radius;
    if (count > best) {
      best = count;
      seed = c;
    }
  }
  // From each pair, the candidate nearer the seed; their median is the origin.
  std::vector<double> xs, ys;
  for (const auto& [p, q] : pairs) {
    const cv::Point2d pick = cv::norm(p - seed) <= cv::norm(q - seed) ? p : q;
    xs.push_back(pick.x);
    ys.push_back(pick.y);
  }
  const cv::Point2d origin(median(xs), median(ys));

  // Mean bearing difference, weighted by distance from the origin (far
  // points give the best-defined bearings).
  double sx = 0, sy = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    if (!use[i]) continue;
    const cv::Point2d v = mirror(pts[i].vision, mirrored);
    const cv::Point2d r = pts[i].robot - origin;
    const double w = cv::norm(v);
    if (w < 1e-9 || cv::norm(r) < 1e-9) continue;
    const double diff = std::atan2(r.y, r.x) - std::atan2(v.y, v.x);
    sx += w * std::cos(diff);
    sy += w * std::sin(diff);
  }
  RigidTransform t;
  t.mirrored = mirrored;
  t.rz_deg = signedDeg(std::atan2(sy, sx) * kDegPerRad);
  t.dx = origin.x;
  t.dy = origin.y;
  return t;
}

// Least median of squares over every two-point hypothesis, for both
// handedness cases: robust to just under half the points being wrong.
std::vector<bool> findInliers(const std::vector<PointPair>& pts, bool* mirrored_out) {
  double best_median = std::numeric_limits<double>::max();
  RigidTransform best;
  for (bool mirrored : {false, true}) {
    for (size_t i = 0; i < pts.size(); ++i) {
      for (size_t j = i + 1; j < pts.size(); ++j) {
        std::vector<bool> use(pts.size(), false);
        use[i] = use[j] = true;
        const RigidTransform t = leastSquares(pts, use, mirrored);
        const double m = median(squaredResiduals(t, pts));
        if (m < best_median) {
          best_median = m;
          best = t;
        }
      }
    }
  }
  *mirrored_out = best.mirrored;
  // Rousseeuw's scale estimate with its small-sample correction.
  const size_t n = pts.size();
  const double scale = 1.4826 * (1.0 + 5.0 / static_cast<double>(std::max<size_t>(n, 3) - 2)) *
                       std::sqrt(best_median);
  // Below a tenth of a millimetre the scale is noise in the noise: never cut
  // tighter than that.
  const double cut = std::max(2.5 * scale, 0.1);
  // Refit on the core and decide inliers against the refit, not the
  // two-point hypothesis.
  std::vector<bool> use(n);
  const auto r0 = squaredResiduals(best, pts);
  for (size_t i = 0; i < n; ++i) use[i] = std::sqrt(r0[i]) <= cut;
  const RigidTransform refit = leastSquares(pts, use, best.mirrored);
  const auto r1 = squaredResiduals(refit, pts);
  for (size_t i = 0; i < n; ++i) use[i] = std::sqrt(r1[i]) <= cut;
  return use;
}

CalibrationResult evaluate(const RigidTransform& t, Method method,
                           const std::vector<PointPair>& pts, const std::vector<bool>& use) {
  CalibrationResult r;
  r.transform = t;
  r.method = method;
  double sum = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    const cv::Point2d d = t.apply(pts[i].vision) - pts[i].robot;
    Residual res{d.x, d.y, cv::norm(d), static_cast<bool>(use[i])};
    if (use[i]) {
      sum += d.dot(d);
      ++r.inliers;
    }
    r.residuals.push_back(res);
  }
  r.rms = r.inliers > 0 ? std::sqrt(sum / r.inliers) : 0;
  return r;
}
}  // namespace

cv::Point2d RigidTransform::apply(cv::Point2d vision) const {
  const cv::Point2d v = mirror(vision, mirrored);
  const double a = rz_deg / kDegPerRad;
  return {dx + std::cos(a) * v.x - std::sin(a) * v.y, dy + std::sin(a) * v.x + std::cos(a) * v.y};
}

double RigidTransform::applyToAngleDeg(double vision_deg) const {
  return picksight::normalizeDeg((mirrored ? -vision_deg : vision_deg) + rz_deg);
}

const char* methodName(Method method) {
  switch (method) {
    case Method::kGeometric:
      return "geometric";
    case Method::kLeastSquares:
      return "lsq";
    case Method::kBest:
      return "best";
  }
  return "?";
}

Result<CalibrationResult> calibrate(const std::vector<PointPair>& points, Method method) {
  if (points.size() < 3) {
    return makeError(CalibrationErrc::kTooFewPoints,
                     "need at least 3 points, have " + std::to_string(points.size()));
  }
  // Spread of the vision points along their minor axis.
  cv::Mat data(static_cast<int>(points.size()), 2, CV_64F);
  for (size_t i = 0; i < points.size(); ++i) {
    data.at<double>(static_cast<int>(i), 0) = points[i].vision.x;
    data.at<double>(static_cast<int>(i), 1) = points[i].vision.y;
  }
  cv::PCA pca(data, cv::Mat(), cv::PCA::DATA_AS_ROW);
  const double minor = std::sqrt(std::max(0.0, pca.eigenvalues.at<double>(1)));
  if (minor < kMinSpreadMm) {
    return makeError(CalibrationErrc::kDegeneratePoints,
                     "the points lie (nearly) on one line: spread them over the work area");
  }
  bool mirrored = false;
  const std::vector<bool> use = findInliers(points, &mirrored);
  const int inliers = static_cast<int>(std::count(use.begin(), use.end(), true));
  if (inliers < 3) {
    return makeError(CalibrationErrc::kTooFewPoints,
                     "fewer than 3 points agree with each other: check the stored points");
  }
  // Cluster radius for the geometric method: a few times the noise level,
  // never below a tenth of a millimetre.
  const RigidTransform lsq = leastSquares(points, use, mirrored);
  CalibrationResult by_lsq = evaluate(lsq, Method::kLeastSquares, points, use);
  if (method == Method::kLeastSquares) return by_lsq;
  const double radius = std::max(0.1, 5 * by_lsq.rms);
  CalibrationResult by_geometry =
      evaluate(geometric(points, use, mirrored, radius), Method::kGeometric, points, use);
  if (method == Method::kGeometric) return by_geometry;
  return by_geometry.rms < by_lsq.rms ? by_geometry : by_lsq;
}

}  // namespace picksight::calibration
