// Robot-camera calibration: the transforms, and the choice of estimator and
// model behind outlier rejection (the estimators are in robot_camera_fits).
#include "picksight/calibration/robot_camera.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>

#include <boost/math/distributions/fisher_f.hpp>

#include "picksight/common/angles.hpp"
#include "robot_camera_fits.hpp"

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

int parameters(TransformModel model) {
  switch (model) {
    case TransformModel::kRigid:
      return 3;
    case TransformModel::kSimilarity:
      return 4;
    case TransformModel::kTilt:
      return 6;
    case TransformModel::kHomography:
      return 8;
  }
  return 8;
}

// Fewest inliers the homography is fitted to; the fewest points for which
// it finds the outliers (its 4-point samples need that many to outvote a
// wrong point) and BEST tries it (below 8 its noise estimate rests on
// fewer than 8 degrees of freedom, and BEST's test, judged against it,
// would rarely tell even a scale error from noise). The same for the tilt's
// 3-point samples and 6 parameters; BEST tries the tilt only where it does
// not try the homography: its second-order error (0.07 mm RMS at 2 degrees)
// hides in 0.05 mm of noise at 8 points or more, where it costs more than
// the homography's two extra parameters.
constexpr int kHomographyMinInliers = 6;
constexpr size_t kHomographyOutlierPoints = 8;
constexpr int kHomographyBestInliers = 8;
constexpr int kTiltMinInliers = 4;
constexpr size_t kTiltOutlierPoints = 6;
constexpr int kTiltBestInliers = 6;
// Cross-validation: every inlier left out in turn up to this many inliers,
// beyond that this many folds (time linear in the number of points).
constexpr size_t kLeaveOneOutMax = 30;
constexpr size_t kFolds = 10;
// BEST's model test: the chance of taking a more general model that only
// fits the noise, and a floor under the noise estimate (a micrometre, below
// any robot's repeatability) so that noise-free points give a finite test.
constexpr double kFalseAlarm = 0.001;
constexpr double kNoiseFloorMm = 0.001;

using Estimator = std::function<std::optional<PlaneTransform>(const std::vector<PointPair>&)>;

Estimator estimator(Method method, bool mirrored, double cluster_radius) {
  switch (method) {
    case Method::kGeometric:
      return [=](const std::vector<PointPair>& p) -> std::optional<PlaneTransform> {
        return PlaneTransform::rigid(fits::geometric(p, mirrored, cluster_radius));
      };
    case Method::kSimilarity:
      return [=](const std::vector<PointPair>& p) -> std::optional<PlaneTransform> {
        return fits::similarity(p, mirrored);
      };
    case Method::kTilt:
      return [=](const std::vector<PointPair>& p) { return fits::tilt(p, mirrored); };
    case Method::kHomography:
      return [](const std::vector<PointPair>& p) { return fits::homography(p); };
    case Method::kLeastSquares:
    case Method::kBest:
      break;
  }
  return [=](const std::vector<PointPair>& p) -> std::optional<PlaneTransform> {
    return PlaneTransform::rigid(fits::rigid(p, mirrored));
  };
}

// RMS error of each inlier predicted by the fit of the others: what a part
// located where no point was stored can expect, the model's extra freedom
// (which only lowers the residuals of the points it was fitted to) included.
double crossValidatedRms(const std::vector<PointPair>& inliers, const Estimator& fit) {
  const size_t n = inliers.size();
  const size_t folds = n <= kLeaveOneOutMax ? n : kFolds;
  double sum = 0;
  for (size_t f = 0; f < folds; ++f) {
    std::vector<PointPair> train, test;
    for (size_t i = 0; i < n; ++i) (i % folds == f ? test : train).push_back(inliers[i]);
    const auto t = train.size() >= 2 ? fit(train) : std::nullopt;
    if (!t) return std::numeric_limits<double>::infinity();
    for (const auto& p : test) {
      const cv::Point2d d = t->apply(p.vision) - p.robot;
      const double e2 = d.dot(d);
      if (!std::isfinite(e2)) return std::numeric_limits<double>::infinity();
      sum += e2;
    }
  }
  return std::sqrt(sum / static_cast<double>(n));
}

// The estimator fitted to the inliers, with every point's residual.
std::optional<CalibrationResult> evaluate(const Estimator& fit, Method method,
                                          const std::vector<PointPair>& pts,
                                          const std::vector<bool>& use) {
  const auto inliers = fits::select(pts, use);
  const auto t = fit(inliers);
  if (!t) return std::nullopt;
  CalibrationResult r;
  r.transform = *t;
  r.method = method;
  double sum = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    const cv::Point2d d = t->apply(pts[i].vision) - pts[i].robot;
    Residual res{d.x, d.y, cv::norm(d), static_cast<bool>(use[i])};
    if (use[i]) {
      sum += d.dot(d);
      ++r.inliers;
    }
    r.residuals.push_back(res);
  }
  r.rms = r.inliers > 0 ? std::sqrt(sum / r.inliers) : 0;
  r.predicted_error = crossValidatedRms(inliers, fit);
  return r;
}

double residualSumOfSquares(const CalibrationResult& r) { return r.rms * r.rms * r.inliers; }

// Whether a model with `simple_k` parameters fits the inliers as well as
// the most general one with `general_k` (rigid in similarity in homography),
// up to the noise: the F-test of the drop in the residual sum of squares
// from one to the other against the general model's noise estimate, over
// 2n coordinates. With Gaussian noise and a simple model that is right, the
// statistic follows Fisher's F(general_k - simple_k, 2n - general_k)
// whatever the noise level and the number of points, so the simple model is
// rejected wrongly with probability kFalseAlarm; a real scale error or tilt
// (millimetres over the work area) makes the statistic hundreds. The noise
// is judged by the general model, which alone fits a tilted camera: judged
// by the similarity's residuals, a tilt would pass for noise. (A fixed
// margin on cross-validated errors, as before, did neither: at 8 to 12
// points their ratio scatters by tens of percent, and BEST took a
// homography fitted to noise on a few cells in a hundred.)
bool fitsAsWell(double simple_rss, int simple_k, double general_rss, int general_k, int inliers) {
  const int dof = 2 * inliers - general_k;
  if (dof < 1 || general_k <= simple_k) return true;
  const double noise2 = std::max(general_rss / dof, kNoiseFloorMm * kNoiseFloorMm);
  const double f = (simple_rss - general_rss) / (general_k - simple_k) / noise2;
  const boost::math::fisher_f_distribution<double> null(general_k - simple_k, dof);
  return !(f > boost::math::quantile(boost::math::complement(null, kFalseAlarm)));
}

Error tooFewAgree() {
  return makeError(CalibrationErrc::kTooFewPoints,
                   "fewer than 3 points agree with each other: check the stored points");
}
}  // namespace

cv::Point2d RigidTransform::apply(cv::Point2d vision) const {
  const cv::Point2d v = mirrored ? cv::Point2d(vision.x, -vision.y) : vision;
  const double a = rz_deg / kDegPerRad;
  return {dx + std::cos(a) * v.x - std::sin(a) * v.y, dy + std::sin(a) * v.x + std::cos(a) * v.y};
}

double RigidTransform::applyToAngleDeg(double vision_deg) const {
  return picksight::normalizeDeg((mirrored ? -vision_deg : vision_deg) + rz_deg);
}

PlaneTransform PlaneTransform::rigid(const RigidTransform& t) {
  PlaneTransform p = similarity(t, 1.0);
  p.model = TransformModel::kRigid;
  return p;
}

PlaneTransform PlaneTransform::similarity(const RigidTransform& t, double scale) {
  PlaneTransform p;
  p.model = TransformModel::kSimilarity;
  const double a = t.rz_deg / kDegPerRad;
  const double c = scale * std::cos(a), s = scale * std::sin(a);
  const double m = t.mirrored ? -1.0 : 1.0;
  p.matrix = cv::Matx33d(c, -s * m, t.dx, s, c * m, t.dy, 0, 0, 1);
  p.dx = t.dx;
  p.dy = t.dy;
  p.rz_deg = signedDeg(t.rz_deg);
  p.scale = scale;
  p.mirrored = t.mirrored;
  return p;
}

Result<PlaneTransform> PlaneTransform::homography(const cv::Matx33d& h) {
  for (int i = 0; i < 9; ++i) {
    if (!std::isfinite(h.val[i]))
      return makeError(CalibrationErrc::kBadInput, "the homography has a non-finite element");
  }
  const double norm = cv::norm(h);
  if (!(norm > 0) || std::abs(h(2, 2)) < 1e-12 * norm ||
      std::abs(cv::determinant(h)) < 1e-15 * std::pow(norm, 3))
    return makeError(CalibrationErrc::kBadInput, "the homography is singular");
  PlaneTransform p;
  p.model = TransformModel::kHomography;
  p.matrix = h * (1.0 / h(2, 2));
  p.dx = p.matrix(0, 2);
  p.dy = p.matrix(1, 2);
  // The local linear map at the vision origin (where w = 1).
  const cv::Matx22d j(
      p.matrix(0, 0) - p.dx * p.matrix(2, 0), p.matrix(0, 1) - p.dx * p.matrix(2, 1),
      p.matrix(1, 0) - p.dy * p.matrix(2, 0), p.matrix(1, 1) - p.dy * p.matrix(2, 1));
  const double det = cv::determinant(j);
  p.mirrored = det < 0;
  p.scale = std::sqrt(std::abs(det));
  p.rz_deg = signedDeg(std::atan2(j(1, 0), j(0, 0)) * kDegPerRad);
  return p;
}

cv::Point2d PlaneTransform::apply(cv::Point2d vision) const {
  const cv::Vec3d q = matrix * cv::Vec3d(vision.x, vision.y, 1);
  return {q[0] / q[2], q[1] / q[2]};
}

double PlaneTransform::applyToAngleDeg(double vision_deg, cv::Point2d at) const {
  const double a = vision_deg / kDegPerRad;
  // The image of a short step along the direction: exact for rigid and
  // similarity, the local direction for a homography.
  const double w = matrix(2, 0) * at.x + matrix(2, 1) * at.y + matrix(2, 2);
  const cv::Point2d p = apply(at);
  const cv::Point2d d(std::cos(a), std::sin(a));
  const cv::Point2d jd(
      ((matrix(0, 0) - p.x * matrix(2, 0)) * d.x + (matrix(0, 1) - p.x * matrix(2, 1)) * d.y) / w,
      ((matrix(1, 0) - p.y * matrix(2, 0)) * d.x + (matrix(1, 1) - p.y * matrix(2, 1)) * d.y) / w);
  return picksight::normalizeDeg(std::atan2(jd.y, jd.x) * kDegPerRad);
}

const char* methodName(Method method) {
  switch (method) {
    case Method::kGeometric:
      return "geometric";
    case Method::kLeastSquares:
      return "lsq";
    case Method::kSimilarity:
      return "similarity";
    case Method::kHomography:
      return "homography";
    case Method::kTilt:
      return "tilt";
    case Method::kBest:
      return "best";
  }
  return "?";
}

const char* modelName(TransformModel model) {
  switch (model) {
    case TransformModel::kRigid:
      return "rigid";
    case TransformModel::kSimilarity:
      return "similarity";
    case TransformModel::kHomography:
      return "homography";
    case TransformModel::kTilt:
      return "tilt";
  }
  return "?";
}

int minimumPoints(Method method) {
  return method == Method::kHomography ? 6 : method == Method::kTilt ? 4 : 3;
}

namespace {
// Enough finite points for `method`, spread over more than a line.
Result<void> checkPoints(const std::vector<PointPair>& points, Method method) {
  const size_t need = static_cast<size_t>(minimumPoints(method));
  if (points.size() < need) {
    return makeError(CalibrationErrc::kTooFewPoints,
                     std::string(methodName(method)) + " needs at least " + std::to_string(need) +
                         " points, have " + std::to_string(points.size()));
  }
  for (size_t i = 0; i < points.size(); ++i) {
    const auto& p = points[i];
    if (!std::isfinite(p.vision.x) || !std::isfinite(p.vision.y) || !std::isfinite(p.robot.x) ||
        !std::isfinite(p.robot.y))
      return makeError(CalibrationErrc::kBadInput,
                       "point " + std::to_string(i + 1) + " has a non-finite coordinate");
  }
  // Spread of the vision points along their minor axis.
  cv::Mat data(static_cast<int>(points.size()), 2, CV_64F);
  for (size_t i = 0; i < points.size(); ++i) {
    data.at<double>(static_cast<int>(i), 0) = points[i].vision.x;
    data.at<double>(static_cast<int>(i), 1) = points[i].vision.y;
  }
  cv::PCA pca(data, cv::Mat(), cv::PCA::DATA_AS_ROW);
  const double minor = std::sqrt(std::max(0.0, pca.eigenvalues.at<double>(1)));
  if (minor < fits::kMinSpreadMm) {
    return makeError(CalibrationErrc::kDegeneratePoints,
                     "the points lie (nearly) on one line: spread them over the work area");
  }
  return {};
}

// The model whose robust fit finds the outliers for `method` on `points`.
TransformModel outlierModel(Method method, size_t points) {
  return method == Method::kSimilarity   ? TransformModel::kSimilarity
         : method == Method::kHomography ? TransformModel::kHomography
         : method == Method::kTilt       ? TransformModel::kTilt
         : method == Method::kBest
             ? (points >= kHomographyOutlierPoints ? TransformModel::kHomography
                : points >= kTiltOutlierPoints     ? TransformModel::kTilt
                                                   : TransformModel::kSimilarity)
             : TransformModel::kRigid;
}

// Cluster radius for the geometric method: a few times the noise level
// (the robust fit's RMS on its `inliers`), never below a tenth of a
// millimetre.
double clusterRadius(const std::vector<PointPair>& points, const fits::RobustFit& robust,
                     int inliers) {
  double ss = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!robust.inliers[i]) continue;
    const cv::Point2d d = robust.transform.apply(points[i].vision) - points[i].robot;
    ss += d.dot(d);
  }
  return std::max(0.1, 5 * std::sqrt(ss / inliers));
}

// BEST: every model on the same inliers. The rigid model is the
// least-squares or the geometric estimate, whichever predicts points left
// out better (they have the same parameters). BEST keeps the stiffest model
// that fits as well as the most general one, within the noise (see
// fitsAsWell).
CalibrationResult bestModel(const std::vector<PointPair>& points, const std::vector<bool>& use,
                            int inliers, bool mirrored, double radius) {
  std::optional<CalibrationResult> rigid;
  double rigid_rss = 0;  // the rigid model's least residuals: least squares'
  for (Method m : {Method::kLeastSquares, Method::kGeometric}) {
    auto r = evaluate(estimator(m, mirrored, radius), m, points, use);
    if (!r) continue;
    if (m == Method::kLeastSquares) rigid_rss = residualSumOfSquares(*r);
    if (!rigid || r->predicted_error < rigid->predicted_error) rigid = std::move(r);
  }
  std::vector<std::pair<CalibrationResult, double>> models;  // stiffest first, with its RSS
  models.emplace_back(*rigid, rigid_rss);
  std::vector<Method> general{Method::kSimilarity};
  if (inliers >= kHomographyBestInliers)
    general.push_back(Method::kHomography);
  else if (inliers >= kTiltBestInliers)
    general.push_back(Method::kTilt);
  for (Method m : general) {
    if (auto r = evaluate(estimator(m, mirrored, radius), m, points, use)) {
      const double rss = residualSumOfSquares(*r);
      models.emplace_back(std::move(*r), rss);
    }
  }
  // From the most general model down: a stiffer one takes its place when it
  // fits as well; the next test is then against the stiffer model's noise
  // estimate, which rests on more degrees of freedom.
  size_t kept = models.size() - 1;
  for (size_t i = kept; i-- > 0;) {
    const auto& [simple, simple_rss] = models[i];
    const auto& [general_fit, general_rss] = models[kept];
    if (fitsAsWell(simple_rss, parameters(simple.transform.model), general_rss,
                   parameters(general_fit.transform.model), inliers))
      kept = i;
    else
      break;
  }
  return models[kept].first;
}
}  // namespace

Result<CalibrationResult> calibrate(const std::vector<PointPair>& points, Method method) {
  if (auto ok = checkPoints(points, method); !ok) return ok.error();
  const auto robust = fits::robustFit(points, outlierModel(method, points.size()));
  if (!robust) {
    return makeError(CalibrationErrc::kDegeneratePoints,
                     "no well-spread subset of the points: spread them over the work area");
  }
  const std::vector<bool>& use = robust->inliers;
  const int inliers = static_cast<int>(std::count(use.begin(), use.end(), true));
  if (inliers < 3) return tooFewAgree();
  const bool mirrored = robust->transform.mirrored;
  const double radius = clusterRadius(points, *robust, inliers);
  if ((method == Method::kHomography && inliers < kHomographyMinInliers) ||
      (method == Method::kTilt && inliers < kTiltMinInliers))
    return tooFewAgree();
  if (method == Method::kBest) return bestModel(points, use, inliers, mirrored, radius);
  auto r = evaluate(estimator(method, mirrored, radius), method, points, use);
  if (!r)
    return makeError(CalibrationErrc::kDegeneratePoints,
                     "the inliers do not determine a homography: spread them over the work area");
  return *r;
}

}  // namespace picksight::calibration
