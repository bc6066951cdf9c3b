// Robot-camera estimators: least squares of the rigid (2D Kabsch),
// similarity (with Umeyama's scale) and homography (normalized DLT) models,
// the paper's geometric method, and least median of squares over minimal
// samples.
#include "robot_camera_fits.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "picksight/common/angles.hpp"

namespace picksight::calibration::fits {
namespace {
using picksight::kDegPerRad;
using picksight::signedDeg;

// Hypotheses tried by least median of squares when the points allow more:
// the chance that none of 500 samples is free of outliers is below 1e-9 for
// 2-point samples with 40 % outliers and for 4-point samples with 30 %.
constexpr size_t kMaxSamples = 500;
constexpr uint64_t kSeed = 0x5eed;
// Geometric method: circle pairs taken at most.
constexpr size_t kMaxCirclePairs = 300;

cv::Point2d mirror(cv::Point2d p, bool mirrored) { return mirrored ? cv::Point2d(p.x, -p.y) : p; }

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

struct Moments {
  cv::Point2d vision_mean, robot_mean;
  double sxx = 0, sxy = 0, syx = 0, syy = 0, vision_var = 0;
};

// Cross-covariance of the (mirrored) vision points with the robot points.
Moments crossMoments(const std::vector<PointPair>& pts, bool mirrored) {
  Moments m;
  for (const auto& p : pts) {
    m.vision_mean += mirror(p.vision, mirrored);
    m.robot_mean += p.robot;
  }
  const double n = static_cast<double>(pts.size());
  m.vision_mean /= n;
  m.robot_mean /= n;
  for (const auto& p : pts) {
    const cv::Point2d a = mirror(p.vision, mirrored) - m.vision_mean;
    const cv::Point2d b = p.robot - m.robot_mean;
    m.sxx += a.x * b.x;
    m.sxy += a.x * b.y;
    m.syx += a.y * b.x;
    m.syy += a.y * b.y;
    m.vision_var += a.dot(a);
  }
  return m;
}

RigidTransform fromRotation(const Moments& m, double theta, double scale, bool mirrored) {
  RigidTransform t;
  t.mirrored = mirrored;
  t.rz_deg = signedDeg(theta * kDegPerRad);
  const double c = scale * std::cos(theta), s = scale * std::sin(theta);
  t.dx = m.robot_mean.x - (c * m.vision_mean.x - s * m.vision_mean.y);
  t.dy = m.robot_mean.y - (s * m.vision_mean.x + c * m.vision_mean.y);
  return t;
}

// Translation and scaling that take points to mean 0 and mean distance sqrt(2).
cv::Matx33d normalizer(const std::vector<cv::Point2d>& pts) {
  cv::Point2d mean(0, 0);
  for (const auto& p : pts) mean += p;
  mean /= static_cast<double>(pts.size());
  double dist = 0;
  for (const auto& p : pts) dist += cv::norm(p - mean);
  dist /= static_cast<double>(pts.size());
  const double s = dist > 0 ? std::sqrt(2.0) / dist : 1.0;
  return {s, 0, -s * mean.x, 0, s, -s * mean.y, 0, 0, 1};
}

cv::Point2d project(const cv::Matx33d& h, cv::Point2d p) {
  const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1);
  return {q[0] / q[2], q[1] / q[2]};
}

// True when three of the points lie within kMinSpreadMm of one line.
bool nearlyCollinear(cv::Point2d a, cv::Point2d b, cv::Point2d c) {
  const double twice_area = std::abs((b - a).cross(c - a));
  const double longest = std::max({cv::norm(b - a), cv::norm(c - a), cv::norm(c - b)});
  return longest < 1e-9 || twice_area / longest < kMinSpreadMm;
}

bool degenerateSample(const std::vector<PointPair>& s) {
  if (s.size() == 2) {
    return cv::norm(s[0].vision - s[1].vision) < kMinSpreadMm ||
           cv::norm(s[0].robot - s[1].robot) < kMinSpreadMm;
  }
  for (size_t i = 0; i < s.size(); ++i) {
    for (size_t j = i + 1; j < s.size(); ++j) {
      for (size_t k = j + 1; k < s.size(); ++k) {
        if (nearlyCollinear(s[i].vision, s[j].vision, s[k].vision) ||
            nearlyCollinear(s[i].robot, s[j].robot, s[k].robot))
          return true;
      }
    }
  }
  return false;
}

// Every combination of `p` indices out of `n` when there are at most
// `max` of them, else `max` random ones (fixed seed).
std::vector<std::vector<size_t>> samples(size_t n, size_t p, size_t max) {
  double count = 1;
  for (size_t i = 0; i < p; ++i)
    count = count * static_cast<double>(n - i) / static_cast<double>(i + 1);
  std::vector<std::vector<size_t>> out;
  if (count <= static_cast<double>(max)) {
    std::vector<size_t> idx(p);
    for (size_t i = 0; i < p; ++i) idx[i] = i;
    while (true) {
      out.push_back(idx);
      size_t i = p;
      while (i > 0 && idx[i - 1] == n - p + i - 1) --i;
      if (i == 0) break;
      ++idx[i - 1];
      for (size_t j = i; j < p; ++j) idx[j] = idx[j - 1] + 1;
    }
    return out;
  }
  std::mt19937_64 rng(kSeed);
  std::uniform_int_distribution<size_t> pick(0, n - 1);
  while (out.size() < max) {
    std::vector<size_t> idx;
    while (idx.size() < p) {
      const size_t k = pick(rng);
      if (std::find(idx.begin(), idx.end(), k) == idx.end()) idx.push_back(k);
    }
    out.push_back(idx);
  }
  return out;
}

std::vector<double> squaredResiduals(const PlaneTransform& t, const std::vector<PointPair>& pts) {
  std::vector<double> r;
  r.reserve(pts.size());
  for (const auto& p : pts) {
    const cv::Point2d d = t.apply(p.vision) - p.robot;
    r.push_back(std::isfinite(d.x) && std::isfinite(d.y) ? d.dot(d)
                                                         : std::numeric_limits<double>::max());
  }
  return r;
}

size_t sampleSize(TransformModel model) {
  return model == TransformModel::kHomography ? 4 : model == TransformModel::kTilt ? 3 : 2;
}
}  // namespace

std::vector<PointPair> select(const std::vector<PointPair>& pts, const std::vector<bool>& use) {
  std::vector<PointPair> out;
  for (size_t i = 0; i < pts.size(); ++i) {
    if (use[i]) out.push_back(pts[i]);
  }
  return out;
}

RigidTransform rigid(const std::vector<PointPair>& pts, bool mirrored) {
  const Moments m = crossMoments(pts, mirrored);
  return fromRotation(m, std::atan2(m.sxy - m.syx, m.sxx + m.syy), 1.0, mirrored);
}

PlaneTransform similarity(const std::vector<PointPair>& pts, bool mirrored) {
  const Moments m = crossMoments(pts, mirrored);
  const double theta = std::atan2(m.sxy - m.syx, m.sxx + m.syy);
  // The scale that minimizes the robot-frame error for that rotation.
  const double scale =
      m.vision_var > 0 ? std::hypot(m.sxx + m.syy, m.sxy - m.syx) / m.vision_var : 1.0;
  return PlaneTransform::similarity(fromRotation(m, theta, scale, mirrored), scale);
}

std::optional<PlaneTransform> homography(const std::vector<PointPair>& pts) {
  if (pts.size() < 4) return std::nullopt;
  std::vector<cv::Point2d> v, r;
  for (const auto& p : pts) {
    v.push_back(p.vision);
    r.push_back(p.robot);
  }
  const cv::Matx33d tv = normalizer(v), tr = normalizer(r);
  // The normal equations A^T A of the DLT system, accumulated: 9 x 9
  // whatever the number of points.
  cv::Matx<double, 9, 9> ata = cv::Matx<double, 9, 9>::zeros();
  for (size_t i = 0; i < pts.size(); ++i) {
    const cv::Point2d a = project(tv, v[i]), b = project(tr, r[i]);
    const cv::Vec<double, 9> row1(-a.x, -a.y, -1, 0, 0, 0, b.x * a.x, b.x * a.y, b.x);
    const cv::Vec<double, 9> row2(0, 0, 0, -a.x, -a.y, -1, b.y * a.x, b.y * a.y, b.y);
    ata += row1 * row1.t() + row2 * row2.t();
  }
  cv::Mat values, vectors;
  cv::eigen(cv::Mat(ata), values, vectors);  // descending: the last row is the solution
  cv::Matx33d hn;
  for (int k = 0; k < 9; ++k) hn(k / 3, k % 3) = vectors.at<double>(8, k);
  auto t = PlaneTransform::homography(tr.inv() * hn * tv);
  if (!t) return std::nullopt;
  // Every point must lie on the near side of the horizon.
  for (const auto& p : v) {
    const cv::Vec3d q = t->matrix * cv::Vec3d(p.x, p.y, 1);
    if (!(q[2] > 0)) return std::nullopt;
  }
  return *t;
}

// A camera tilted by t about an axis in the plane sees the plane through the
// homography K R K^-1 (K: its focal length f, R: the tilt): to first order
// in t, an identity whose last row is (w, 1) with |w| = t / f, plus a shift.
// What is left of the 2 x 2 block departs from a similarity by t^2 / 2 (6e-4
// at 2 degrees), and the shift times w is of the same order once both
// frames are taken about their points' centroids. So about the centroids:
// robot = (s R vision + t) / (1 + w . vision), linear in (s R, t, w) once
// multiplied out: 6 unknowns, least squares. Two fewer parameters than the
// full homography, which then bends less to the noise of a few points.
std::optional<PlaneTransform> tilt(const std::vector<PointPair>& pts, bool mirrored) {
  if (pts.size() < 3) return std::nullopt;
  const Moments m = crossMoments(pts, mirrored);
  // Unit spread (sqrt 2 on average) for a well-conditioned system.
  const double spread = std::sqrt(m.vision_var / static_cast<double>(pts.size()) / 2);
  if (!(spread > 0)) return std::nullopt;
  const double k = 1.0 / spread;
  cv::Mat a(static_cast<int>(2 * pts.size()), 6, CV_64F), b(a.rows, 1, CV_64F);
  for (size_t i = 0; i < pts.size(); ++i) {
    const cv::Point2d v = (mirror(pts[i].vision, mirrored) - m.vision_mean) * k;
    const cv::Point2d r = (pts[i].robot - m.robot_mean) * k;
    const int row = static_cast<int>(2 * i);
    const double ex[6] = {v.x, -v.y, 1, 0, -r.x * v.x, -r.x * v.y};
    const double ey[6] = {v.y, v.x, 0, 1, -r.y * v.x, -r.y * v.y};
    for (int c = 0; c < 6; ++c) {
      a.at<double>(row, c) = ex[c];
      a.at<double>(row + 1, c) = ey[c];
    }
    b.at<double>(row) = r.x;
    b.at<double>(row + 1) = r.y;
  }
  cv::Mat x;
  if (!cv::solve(a, b, x, cv::DECOMP_SVD)) return std::nullopt;
  const auto q = [&](int i) { return x.at<double>(i); };
  // Centred, unit-spread vision -> centred, unit-spread robot; then undo both.
  const cv::Matx33d centred(q(0), -q(1), q(2), q(1), q(0), q(3), q(4), q(5), 1);
  const double mv = mirrored ? -1.0 : 1.0;
  const cv::Matx33d from_vision(k, 0, -k * m.vision_mean.x, 0, k * mv, -k * m.vision_mean.y, 0, 0,
                                1);
  const cv::Matx33d to_robot(spread, 0, m.robot_mean.x, 0, spread, m.robot_mean.y, 0, 0, 1);
  auto t = PlaneTransform::homography(to_robot * centred * from_vision);
  if (!t) return std::nullopt;
  for (const auto& p : pts) {
    const cv::Vec3d h = t->matrix * cv::Vec3d(p.vision.x, p.vision.y, 1);
    if (!(h[2] > 0)) return std::nullopt;
  }
  t->model = TransformModel::kTilt;
  return *t;
}

// A rigid motion keeps distances, so the vision origin, seen in the robot
// frame, lies at distance |v_i| from every robot point r_i: on a circle
// around each. Pairs of circles intersect in two candidates; the right ones
// cluster at the origin. The rotation then follows from each point's bearing
// from that origin in both frames (the law of cosines in the paper; bearings
// here).
RigidTransform geometric(const std::vector<PointPair>& pts, bool mirrored, double cluster_radius) {
  std::vector<std::pair<size_t, size_t>> circle_pairs;
  for (const auto& s : samples(pts.size(), 2, kMaxCirclePairs))
    circle_pairs.emplace_back(s[0], s[1]);
  std::vector<cv::Point2d> candidates;
  std::vector<std::pair<cv::Point2d, cv::Point2d>> pairs;
  for (const auto& [i, j] : circle_pairs) {
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
  for (const auto& p : pts) {
    const cv::Point2d v = mirror(p.vision, mirrored);
    const cv::Point2d r = p.robot - origin;
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

std::optional<PlaneTransform> fitModel(const std::vector<PointPair>& pts, TransformModel model,
                                       bool mirrored) {
  switch (model) {
    case TransformModel::kRigid:
      return PlaneTransform::rigid(rigid(pts, mirrored));
    case TransformModel::kSimilarity:
      return similarity(pts, mirrored);
    case TransformModel::kTilt:
      return tilt(pts, mirrored);
    case TransformModel::kHomography:
      return homography(pts);
  }
  return std::nullopt;
}

std::optional<RobustFit> robustFit(const std::vector<PointPair>& pts, TransformModel model) {
  const size_t n = pts.size();
  const size_t p = sampleSize(model);
  if (n < p) return std::nullopt;
  // Rousseeuw's order statistic for p-point samples: robust to just under
  // half the points being wrong. Never one of the sample's own p residuals,
  // which are zero: with few points (3 for a similarity) the scale would be
  // zero and every point outside the sample an outlier.
  const size_t h = std::min(n - 1, std::max(p, n / 2 + (p + 1) / 2 - 1));
  double best_score = std::numeric_limits<double>::max();
  std::optional<PlaneTransform> best;
  const auto handedness = model == TransformModel::kHomography ? std::vector<bool>{false}
                                                               : std::vector<bool>{false, true};
  std::vector<PointPair> sample(p);
  for (const auto& idx : samples(n, p, kMaxSamples)) {
    for (size_t k = 0; k < p; ++k) sample[k] = pts[idx[k]];
    if (degenerateSample(sample)) continue;
    for (bool mirrored : handedness) {
      const auto t = fitModel(sample, model, mirrored);
      if (!t) continue;
      auto r = squaredResiduals(*t, pts);
      std::nth_element(r.begin(), r.begin() + static_cast<long>(h), r.end());
      if (r[h] < best_score) {
        best_score = r[h];
        best = t;
      }
    }
  }
  if (!best) return std::nullopt;
  // Rousseeuw's scale estimate with its small-sample correction.
  const double correction = n > p ? 1.0 + 5.0 / static_cast<double>(n - p) : 6.0;
  const double scale = 1.4826 * correction * std::sqrt(best_score);
  // Below a tenth of a millimetre the scale is noise in the noise: never cut
  // tighter than that.
  const double cut2 = std::pow(std::max(2.5 * scale, 0.1), 2);
  // Refit on the core and decide inliers against the refit, not the
  // minimal-sample hypothesis. A homography from 4 noisy points (or a tilt
  // from 3) extrapolates poorly: its core takes every point within 3 cuts,
  // so that a genuine point far from the sample is not judged by a fit made
  // without it (the mis-touched points it must reject are millimetres off).
  // Measured on 300 tilted cells of 7 points spread over the work area:
  // 4 genuine points cut, 24 with the tilt's core at one cut. What no core
  // can do is judge a point that lies far beyond all the others (250 mm
  // out from eleven in a 100 mm square): only it fixes the perspective out
  // there, so a fit without it cannot predict it and a fit with it bends to
  // it. The tilt cuts such a genuine point in 63 of 300 layouts and keeps
  // one touched 1 mm off in 148 (the homography 73 and 153; least squares,
  // with no perspective to bend, 1 and none): spread the points over the
  // work area, to its corners when the camera may be tilted (docs/PROTOCOL.md).
  const double core2 =
      model == TransformModel::kHomography || model == TransformModel::kTilt ? 9 * cut2 : cut2;
  RobustFit fit;
  fit.inliers.assign(n, false);
  const auto r0 = squaredResiduals(*best, pts);
  for (size_t i = 0; i < n; ++i) fit.inliers[i] = r0[i] <= core2;
  const auto refit = fitModel(select(pts, fit.inliers), model, best->mirrored);
  fit.transform = refit ? *refit : *best;
  const auto r1 = squaredResiduals(fit.transform, pts);
  for (size_t i = 0; i < n; ++i) fit.inliers[i] = r1[i] <= cut2;
  return fit;
}

}  // namespace picksight::calibration::fits
