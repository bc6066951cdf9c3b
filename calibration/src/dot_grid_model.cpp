// Homography and radial distortion fitted to a measured dot grid.
#include "picksight/calibration/dot_grid_model.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <opencv2/calib3d.hpp>

#include "picksight/calibration/calibration_errors.hpp"
#include "picksight/common/angles.hpp"

namespace picksight::calibration {
namespace {

constexpr double kLensReach = 0.6;  // of the half-diagonal, see the header
constexpr int kIterations = 60;

cv::Point2d project(const cv::Matx33d& h, cv::Point2d p) {
  const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1);
  return {q[0] / q[2], q[1] / q[2]};
}

// Normalized homography (8 entries, h22 = 1) and radial terms (k1, k2), on
// unit-spread grid and image coordinates for a well-conditioned problem.
using Params = std::array<double, 10>;

cv::Matx33d homographyOf(const Params& p) {
  return {p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], 1};
}

cv::Point2d distorted(const Params& p, cv::Point2d grid) {
  const cv::Point2d u = project(homographyOf(p), grid);
  const double r2 = u.dot(u);
  return u * (1 + p[8] * r2 + p[9] * r2 * r2);
}

// Levenberg-Marquardt on the image residuals, numeric Jacobian: ten
// parameters and at most a few hundred dots, so cost is no concern.
Params refine(Params p, const std::vector<cv::Point2d>& grid, const std::vector<cv::Point2d>& img,
              int free) {
  const auto residuals = [&](const Params& q) {
    cv::Mat r(static_cast<int>(2 * grid.size()), 1, CV_64F);
    for (size_t i = 0; i < grid.size(); ++i) {
      const cv::Point2d d = distorted(q, grid[i]) - img[i];
      r.at<double>(static_cast<int>(2 * i)) = d.x;
      r.at<double>(static_cast<int>(2 * i + 1)) = d.y;
    }
    return r;
  };
  double lambda = 1e-3;
  cv::Mat r = residuals(p);
  double cost = r.dot(r);
  for (int it = 0; it < kIterations; ++it) {
    cv::Mat jac(r.rows, free, CV_64F);
    for (int k = 0; k < free; ++k) {
      Params hi = p, lo = p;
      const double step = 1e-7 * std::max(1.0, std::abs(p[static_cast<size_t>(k)]));
      hi[static_cast<size_t>(k)] += step;
      lo[static_cast<size_t>(k)] -= step;
      cv::Mat(residuals(hi) - residuals(lo)).copyTo(jac.col(k));
      jac.col(k) /= 2 * step;
    }
    const cv::Mat jtj = jac.t() * jac, jtr = jac.t() * r;
    bool improved = false;
    while (lambda < 1e10) {
      cv::Mat a = jtj.clone();
      for (int k = 0; k < free; ++k) a.at<double>(k, k) *= 1 + lambda;
      cv::Mat delta;
      if (!cv::solve(a, -jtr, delta, cv::DECOMP_CHOLESKY)) break;
      Params next = p;
      for (int k = 0; k < free; ++k) next[static_cast<size_t>(k)] += delta.at<double>(k);
      const cv::Mat rn = residuals(next);
      const double c = rn.dot(rn);
      if (c < cost) {
        const bool converged = cost - c < 1e-14 * std::max(cost, 1e-30);
        p = next;
        r = rn;
        cost = c;
        lambda = std::max(lambda / 10, 1e-12);
        improved = !converged;
        break;
      }
      lambda *= 10;
    }
    if (!improved) break;
  }
  return p;
}

// Takes grid millimetres to unit spread about their mean, and back.
cv::Matx33d normalizer(const std::vector<cv::Point2d>& pts) {
  cv::Point2d mean(0, 0);
  for (const auto& q : pts) mean += q;
  mean *= 1.0 / static_cast<double>(pts.size());
  double spread = 0;
  for (const auto& q : pts) spread += cv::norm(q - mean);
  spread /= static_cast<double>(pts.size());
  const double k = spread > 0 ? 1 / spread : 1;
  return {k, 0, -k * mean.x, 0, k, -k * mean.y, 0, 0, 1};
}

// Where image coordinates are measured from, and in what unit: about the
// centre of distortion (the sensor's middle when known), in units of the
// half-diagonal; and whether the dots reach far enough from it for the
// radial terms to be fitted.
struct ImageUnits {
  cv::Point2d middle;
  double half_diagonal = 0;
  bool radial = false;
};

ImageUnits imageUnits(const std::vector<cv::Point2d>& img, bool lens_known,
                      std::optional<cv::Size> sensor, bool projective) {
  ImageUnits u;
  for (const auto& q : img) u.middle += q;
  u.middle *= 1.0 / static_cast<double>(img.size());
  for (const auto& q : img) u.half_diagonal = std::max(u.half_diagonal, cv::norm(q - u.middle));
  if (sensor && !lens_known && projective) {
    u.middle = {(sensor->width - 1) / 2.0, (sensor->height - 1) / 2.0};
    u.half_diagonal = std::hypot(sensor->width, sensor->height) / 2;
    double reach = 0;
    for (const auto& q : img) reach = std::max(reach, cv::norm(q - u.middle));
    u.radial = reach >= kLensReach * u.half_diagonal;
  }
  return u;
}

// The grid-to-image parameters on unit coordinates (`gn` grid, `un` image):
// a homography refined with the radial terms when they are free, else the
// 6 entries of an affine map by least squares.
Result<Params> fitParams(const std::vector<cv::Point2d>& gn, const std::vector<cv::Point2d>& un,
                         bool projective, bool radial) {
  Params p{};
  if (projective) {
    const cv::Mat h0 = cv::findHomography(gn, un, 0);
    if (h0.empty()) return makeError(CalibrationErrc::kBadTarget, "the dots fit no homography");
    cv::Matx33d h(h0);
    h *= 1 / h(2, 2);
    for (int k = 0; k < 8; ++k) p[static_cast<size_t>(k)] = h.val[k];
    return refine(p, gn, un, radial ? 10 : 8);
  }
  // Affine only: the 6 entries of the top two rows by least squares.
  cv::Mat a(static_cast<int>(2 * gn.size()), 6, CV_64F, cv::Scalar(0)), b(a.rows, 1, CV_64F);
  for (size_t i = 0; i < gn.size(); ++i) {
    const int row = static_cast<int>(2 * i);
    const double g[3] = {gn[i].x, gn[i].y, 1};
    for (int c = 0; c < 3; ++c) {
      a.at<double>(row, c) = g[c];
      a.at<double>(row + 1, 3 + c) = g[c];
    }
    b.at<double>(row) = un[i].x;
    b.at<double>(row + 1) = un[i].y;
  }
  cv::Mat x;
  if (!cv::solve(a, b, x, cv::DECOMP_SVD))
    return makeError(CalibrationErrc::kBadTarget, "the dots fit no grid");
  for (int k = 0; k < 6; ++k) p[static_cast<size_t>(k)] = x.at<double>(k);
  return p;
}

// The grid as the camera sees it about the dots' middle `m`: `j`, grid
// millimetres per pixel there (the grid turned to the image's handedness),
// their scale, and the rectification that takes ideal sensor pixels to a
// fronto-parallel image of the same scale, orientation and middle.
struct GridView {
  cv::Matx22d j;
  double mm_per_px = 0;
  cv::Matx33d rectify;
};

Result<GridView> gridView(const cv::Matx33d& pixel_to_grid_raw, cv::Point2d m) {
  const auto jacobian = [&](const cv::Matx33d& g) {
    const double e = 1e-3;
    const cv::Point2d dx =
        (project(g, m + cv::Point2d(e, 0)) - project(g, m - cv::Point2d(e, 0))) / (2 * e);
    const cv::Point2d dy =
        (project(g, m + cv::Point2d(0, e)) - project(g, m - cv::Point2d(0, e))) / (2 * e);
    return cv::Matx22d(dx.x, dy.x, dx.y, dy.y);
  };
  // The grid's own handedness is arbitrary: take it as the image's.
  cv::Matx33d pixel_to_grid = pixel_to_grid_raw;
  if (cv::determinant(jacobian(pixel_to_grid)) < 0)
    pixel_to_grid = cv::Matx33d(1, 0, 0, 0, -1, 0, 0, 0, 1) * pixel_to_grid;
  GridView view;
  view.j = jacobian(pixel_to_grid);  // mm per pixel at the middle
  const cv::Matx22d& j = view.j;
  const double mm_per_px = std::sqrt(cv::determinant(j));
  if (!(mm_per_px > 0) || !std::isfinite(mm_per_px))
    return makeError(CalibrationErrc::kBadTarget, "the grid's scale cannot be measured");
  view.mm_per_px = mm_per_px;
  // The rotation nearest to j (2 x 2 polar decomposition), so that the
  // rectified image keeps the camera's own orientation and the dots' middle.
  const double angle = std::atan2(j(1, 0) - j(0, 1), j(0, 0) + j(1, 1));
  const double c = std::cos(angle), s = std::sin(angle);
  // Rectified pixel = m + R^T (grid - gm) / mm_per_px.
  const cv::Matx33d grid_to_rectified(c / mm_per_px, s / mm_per_px, 0, -s / mm_per_px,
                                      c / mm_per_px, 0, 0, 0, 1);
  cv::Matx33d rectify = grid_to_rectified * pixel_to_grid;
  const cv::Point2d shift = m - project(rectify, m);
  rectify = cv::Matx33d(1, 0, shift.x, 0, 1, shift.y, 0, 0, 1) * rectify;
  rectify *= 1 / rectify(2, 2);
  view.rectify = rectify;
  return view;
}

}  // namespace

Result<DotGridModel> fitDotGrid(const std::vector<cv::Point2d>& centres,
                                const std::vector<cv::Point2i>& indices, double pitch_mm,
                                const std::optional<LensModel>& lens,
                                std::optional<cv::Size> sensor) {
  if (centres.size() != indices.size() || centres.size() < 4)
    return makeError(CalibrationErrc::kBadTarget, "a dot grid needs at least 2 x 2 dots");
  if (!(pitch_mm > 0) || !std::isfinite(pitch_mm))
    return makeError(CalibrationErrc::kBadInput, "the grid pitch must be positive");
  std::vector<cv::Point2d> img = lens ? lens->undistort(centres) : centres;
  std::vector<cv::Point2d> grid;
  int min_i = indices[0].x, max_i = min_i, min_j = indices[0].y, max_j = min_j;
  for (const auto& ij : indices) {
    grid.emplace_back(ij.x * pitch_mm, ij.y * pitch_mm);
    min_i = std::min(min_i, ij.x);
    max_i = std::max(max_i, ij.x);
    min_j = std::min(min_j, ij.y);
    max_j = std::max(max_j, ij.y);
  }
  const bool projective = centres.size() >= 9 && max_i - min_i >= 2 && max_j - min_j >= 2;

  const ImageUnits units = imageUnits(img, lens.has_value(), sensor, projective);
  const cv::Point2d middle = units.middle;
  const double half_diagonal = units.half_diagonal;
  const bool radial = units.radial;
  if (!(half_diagonal > 0)) return makeError(CalibrationErrc::kBadTarget, "the dots coincide");
  const cv::Matx33d to_unit(1 / half_diagonal, 0, -middle.x / half_diagonal, 0, 1 / half_diagonal,
                            -middle.y / half_diagonal, 0, 0, 1);
  const cv::Matx33d grid_unit = normalizer(grid);
  std::vector<cv::Point2d> gn, un;
  for (size_t i = 0; i < img.size(); ++i) {
    gn.push_back(project(grid_unit, grid[i]));
    un.push_back(project(to_unit, img[i]));
  }
  const auto fitted = fitParams(gn, un, projective, radial);
  if (!fitted) return fitted.error();
  const Params& p = *fitted;

  DotGridModel model;
  double ss = 0;
  for (size_t i = 0; i < gn.size(); ++i) {
    const cv::Point2d d = (distorted(p, gn[i]) - un[i]) * half_diagonal;
    ss += d.dot(d);
  }
  model.rms_px = std::sqrt(ss / static_cast<double>(gn.size()));
  if (radial) {
    LensModel l;
    l.image_size = *sensor;
    l.camera_matrix = cv::Matx33d(half_diagonal, 0, middle.x, 0, half_diagonal, middle.y, 0, 0, 1);
    l.distortion = {p[8], p[9], 0, 0, 0};
    l.rms_reprojection_px = model.rms_px;
    l.views = 1;
    model.lens = l;
    img = l.undistort(centres);
  }

  // Grid millimetres to ideal sensor pixels, and its inverse.
  cv::Matx33d h = to_unit.inv() * homographyOf(p) * grid_unit;
  if (!projective) h(2, 0) = h(2, 1) = 0;
  cv::Point2d m(0, 0);
  for (const auto& q : img) m += q;
  m *= 1.0 / static_cast<double>(img.size());
  const auto view = gridView(h.inv(), m);
  if (!view) return view.error();
  const cv::Matx22d& j = view->j;

  model.scale.mm_per_px_x = model.scale.mm_per_px_y = view->mm_per_px;
  if (!projective) {
    // Too few dots for a tilt: the scale on X and on Y separately, from the
    // pixels per millimetre B = j^-1 (B B^T = diag(1/sx^2, 1/sy^2) whatever
    // the grid's rotation), as for a camera with pixels that are not square.
    const cv::Matx22d b = j.inv();
    model.scale.mm_per_px_x = 1 / std::hypot(b(0, 0), b(0, 1));
    model.scale.mm_per_px_y = 1 / std::hypot(b(1, 0), b(1, 1));
  }
  if (projective) {
    model.scale.rectify = view->rectify;
    for (const auto& q : img)
      model.perspective_px =
          std::max(model.perspective_px, cv::norm(project(view->rectify, q) - q));
  }
  return model;
}

}  // namespace picksight::calibration
