// Region extraction: labels first (one pass over the image), then per-region
// work limited to the region's bounding box.
#include "picksight/vision/regions.hpp"

#include <algorithm>
#include <cmath>

namespace picksight::vision {

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
  if (backward > forward) deg += 180.0;
  deg = std::fmod(deg, 360.0);
  if (deg < 0) deg += 360.0;
  return deg;
}

namespace {
// Below this relative contrast between part and background, coverage read
// from grey levels is mostly noise; the binary moments are kept.
constexpr double kMinContrast = 0.08;
// Darker backgrounds (grey levels) are not lit: see greyMoments.
constexpr double kMinLitBackground = 16;

// Least-squares plane z = a + b x + c y through the grey levels of the pixels
// of `where` in `grey` (box coordinates). False when too few or degenerate.
bool fitPlane(const cv::Mat& grey, const cv::Mat& where, cv::Vec3d* plane) {
  cv::Matx33d normal = cv::Matx33d::zeros();
  cv::Vec3d rhs(0, 0, 0);
  int n = 0;
  for (int y = 0; y < grey.rows; ++y) {
    const uint8_t* g = grey.ptr<uint8_t>(y);
    const uint8_t* w = where.ptr<uint8_t>(y);
    for (int x = 0; x < grey.cols; ++x) {
      if (!w[x]) continue;
      const cv::Vec3d v(1.0, x, y);
      normal += v * v.t();
      rhs += v * static_cast<double>(g[x]);
      ++n;
    }
  }
  if (n < 8) return false;
  cv::Vec3d solution;
  if (!cv::solve(normal, rhs, solution, cv::DECOMP_CHOLESKY)) return false;
  *plane = solution;
  return true;
}

// Grey-level coverage moments of region `label` (see findRegions). Returns
// false, leaving the moments alone, when the grey levels cannot be trusted.
//
// Light falls unevenly, and a part reflects a fixed fraction of the light
// that reaches it, so grey levels are read relative to the local background:
// a plane fitted to a ring of background around the part gives the light at
// every pixel, R = I / background is the reflectance ratio, and a pixel's
// coverage is (1 - R) / (1 - R_part). Constant levels instead would weigh one
// side of a part more than the other and pull its centroid by a tenth of a
// pixel under a few percent of light gradient.
bool greyMoments(const cv::Mat& grey, const cv::Mat& labels, int label, const cv::Rect& bbox,
                 cv::Moments* moments, cv::Point2d* centroid, cv::Mat* weights, cv::Point* origin) {
  const cv::Rect box =
      (bbox + cv::Size(8, 8) - cv::Point(4, 4)) & cv::Rect(0, 0, grey.cols, grey.rows);
  const cv::Mat own = labels(box) == label;
  const cv::Mat free = labels(box) == 0;
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3));
  cv::Mat interior;
  cv::Mat near;
  cv::Mat far;
  cv::erode(own, interior, kernel, cv::Point(-1, -1), 2);
  cv::dilate(own, near, kernel, cv::Point(-1, -1), 2);
  cv::dilate(own, far, kernel, cv::Point(-1, -1), 4);
  // Background from a ring just outside the edge blur, free of other parts.
  const cv::Mat ring = far & ~near & free;
  if (cv::countNonZero(interior) < 8) return false;
  cv::Vec3d plane;
  if (!fitPlane(grey(box), ring, &plane)) return false;

  cv::Mat background(box.size(), CV_32F);
  for (int y = 0; y < box.height; ++y) {
    float* b = background.ptr<float>(y);
    for (int x = 0; x < box.width; ++x)
      b[x] = static_cast<float>(plane[0] + plane[1] * x + plane[2] * y);
  }
  cv::Mat level;
  grey(box).convertTo(level, CV_32F);
  cv::Mat coverage;
  double min_background = 0;
  cv::minMaxLoc(background, &min_background);
  if (min_background >= kMinLitBackground) {
    cv::Mat ratio;
    cv::divide(level, background, ratio);
    const double contrast = 1.0 - cv::mean(ratio, interior)[0];
    if (std::abs(contrast) < kMinContrast) return false;
    ratio.convertTo(coverage, CV_32F, -1.0 / contrast, 1.0 / contrast);
  } else {
    // A black background carries no light to divide by: parts are lit on
    // their own, and levels are read against the background additively.
    const cv::Mat offset = level - background;
    const double contrast = cv::mean(offset, interior)[0];
    if (std::abs(contrast) < kMinContrast * 255) return false;
    offset.convertTo(coverage, CV_32F, 1.0 / contrast);
  }
  cv::min(cv::max(coverage, 0.0), 1.0, coverage);
  // Only the region and its blurred edge count, never a neighbour's pixels.
  coverage.setTo(0, ~(near & (free | own)));
  const cv::Moments m = cv::moments(coverage, false);
  if (m.m00 <= 0) return false;
  *moments = m;
  *centroid = cv::Point2d(box.x + m.m10 / m.m00, box.y + m.m01 / m.m00);
  *weights = coverage;
  *origin = box.tl();
  return true;
}
}  // namespace

std::vector<Region> findRegions(const cv::Mat& mask, const RegionOptions& options,
                                const cv::Mat& grey) {
  CV_Assert(mask.type() == CV_8UC1);
  CV_Assert(grey.empty() || (grey.type() == CV_8UC1 && grey.size() == mask.size()));
  cv::Mat labels;
  cv::Mat stats;
  cv::Mat centroids;
  const int count = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  std::vector<Region> regions;
  for (int label = 1; label < count; ++label) {
    const int area = stats.at<int>(label, cv::CC_STAT_AREA);
    if (area < options.min_area) continue;
    const cv::Rect bbox(
        stats.at<int>(label, cv::CC_STAT_LEFT), stats.at<int>(label, cv::CC_STAT_TOP),
        stats.at<int>(label, cv::CC_STAT_WIDTH), stats.at<int>(label, cv::CC_STAT_HEIGHT));
    const bool border =
        bbox.x == 0 || bbox.y == 0 || bbox.br().x == mask.cols || bbox.br().y == mask.rows;
    if (border && !options.keep_border_regions) continue;

    Region r;
    r.bbox = bbox;
    r.touches_border = border;
    // The region alone, in its box with a one-pixel frame so its boundary is
    // closed even where it touches the box edge.
    cv::Mat local(bbox.height + 2, bbox.width + 2, CV_8UC1, cv::Scalar(0));
    cv::Mat inner = local(cv::Rect(1, 1, bbox.width, bbox.height));
    cv::compare(labels(bbox), cv::Scalar(label), inner, cv::CMP_EQ);

    const cv::Moments m = cv::moments(inner, true);
    r.moments = m;
    r.area = m.m00;
    r.centroid = cv::Point2d(bbox.x + m.m10 / m.m00, bbox.y + m.m01 / m.m00);

    std::vector<std::vector<cv::Point>> contours;
    std::vector<cv::Vec4i> hierarchy;
    cv::findContours(local, contours, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE,
                     cv::Point(bbox.x - 1, bbox.y - 1));
    for (size_t i = 0; i < contours.size(); ++i) {
      if (hierarchy[i][3] < 0) {
        if (contours[i].size() > r.outer.size()) r.outer = std::move(contours[i]);
      } else {
        r.hole_boundaries.push_back(std::move(contours[i]));
      }
    }
    r.holes = static_cast<int>(r.hole_boundaries.size());

    if (!grey.empty() && greyMoments(grey, labels, label, bbox, &r.moments, &r.centroid,
                                     &r.coverage, &r.coverage_origin)) {
      r.area = r.moments.m00;
    } else {
      inner.convertTo(r.coverage, CV_32F, 1.0 / 255.0);
      r.coverage_origin = bbox.tl();
    }
    r.angle_deg = orientationDeg(r.moments, r.centroid, r.outer);
    const cv::Moments& rm = r.moments;
    const double common =
        std::sqrt((rm.mu20 - rm.mu02) * (rm.mu20 - rm.mu02) + 4 * rm.mu11 * rm.mu11);
    const double major = rm.mu20 + rm.mu02 + common;
    const double minor = rm.mu20 + rm.mu02 - common;
    r.elongation = major > 0 ? 1.0 - minor / major : 0;
    regions.push_back(std::move(r));
  }
  std::sort(regions.begin(), regions.end(),
            [](const Region& a, const Region& b) { return a.area > b.area; });
  return regions;
}

}  // namespace picksight::vision
