// Blob features: closed-form measures of one region.
#include "picksight/vision/segmentation/blob_features.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

#include "picksight/common/angles.hpp"

namespace picksight::vision {

HuArray huInvariants(const cv::Moments& m) {
  HuArray hu{};
  cv::HuMoments(m, hu.data());
  return hu;
}

HuArray logHu(const HuArray& hu) {
  HuArray h{};
  for (size_t i = 0; i < hu.size(); ++i) {
    h[i] = hu[i] == 0 ? 0.0 : -std::copysign(1.0, hu[i]) * std::log10(std::abs(hu[i]));
  }
  return h;
}

namespace {
// The extent of a convex polygon (its vertices in turn, no three in a
// line; see extentOf).
Extent extentOfHull(const std::vector<cv::Point2d>& hull) {
  Extent e;
  const size_t n = hull.size();
  if (n < 3) {
    e.diameter = n == 2 ? cv::norm(hull[1] - hull[0]) : 0;
    return e;
  }
  // Rotating calipers: both are reached at the hull's vertices, the width
  // with one side of the strip on a hull edge, the diameter between a
  // vertex and the one farthest from an edge next to it. The farthest
  // vertex from each edge in turn moves round the hull one way, so each
  // is found in one pass (a blob's hull has hundreds of vertices: every
  // pair of them cost the blob search 4 % of a LOCATE ALL).
  const auto at = [&](size_t i) { return hull[i % n]; };
  const auto height = [&](size_t i, size_t k) {  // vertex k over edge i, times its length
    return std::abs((at(i + 1) - at(i)).cross(at(k) - at(i)));
  };
  e.width = std::numeric_limits<double>::max();
  size_t far = 1;
  for (size_t i = 0; i < n; ++i) {
    if (far <= i) far = i + 1;
    for (size_t steps = 0; steps < n && height(i, far + 1) >= height(i, far); ++steps) ++far;
    const double length = cv::norm(at(i + 1) - at(i));
    if (length > 0) e.width = std::min(e.width, height(i, far) / length);
    // The farthest vertex and the next (an edge parallel to edge i ties).
    for (const size_t k : {far, far + 1}) {
      e.diameter = std::max({e.diameter, cv::norm(at(k) - at(i)), cv::norm(at(k) - at(i + 1))});
    }
  }
  if (e.width == std::numeric_limits<double>::max()) e.width = 0;
  return e;
}

// (b - o) x (c - o), exact for pixel coordinates.
int64_t turnOf(cv::Point o, cv::Point b, cv::Point c) {
  return static_cast<int64_t>(b.x - o.x) * (c.y - o.y) -
         static_cast<int64_t>(b.y - o.y) * (c.x - o.x);
}
}  // namespace

Extent extentOf(const std::vector<cv::Point2f>& points) {
  if (points.size() < 2) return {};
  std::vector<cv::Point2f> hull;
  cv::convexHull(points, hull);
  return extentOfHull(std::vector<cv::Point2d>(hull.begin(), hull.end()));
}

Extent extentOfOutline(const std::vector<cv::Point>& outline) {
  if (outline.size() < 2) return {};
  // The hull of a set of pixels is that of each row's first and last: an
  // outline's thousands of points become two a row, already in order of
  // rows, and the hull is one pass each way over them (Andrew's monotone
  // chain) instead of cv::convexHull's sort (29 us against 4, a mean over
  // the outlines of the front-light benchmark's frames).
  int top = outline.front().y;
  int bottom = top;
  for (const cv::Point& p : outline) {
    top = std::min(top, p.y);
    bottom = std::max(bottom, p.y);
  }
  const auto rows = static_cast<size_t>(bottom - top + 1);
  std::vector<int> first(rows, std::numeric_limits<int>::max());
  std::vector<int> last(rows, std::numeric_limits<int>::min());
  for (const cv::Point& p : outline) {
    const auto row = static_cast<size_t>(p.y - top);
    first[row] = std::min(first[row], p.x);
    last[row] = std::max(last[row], p.x);
  }
  std::vector<cv::Point> ends;  // by row, then column
  for (size_t row = 0; row < rows; ++row) {
    if (first[row] > last[row]) continue;
    const int y = top + static_cast<int>(row);
    ends.emplace_back(first[row], y);
    if (last[row] != first[row]) ends.emplace_back(last[row], y);
  }
  // One chain down the rows, one back up; a turn that is not strictly one
  // way drops the middle point (no three vertices in a line).
  std::vector<cv::Point> hull(2 * ends.size());
  size_t k = 0;
  for (const cv::Point& p : ends) {
    while (k >= 2 && turnOf(hull[k - 2], hull[k - 1], p) <= 0) --k;
    hull[k++] = p;
  }
  for (size_t i = ends.size() - 1, lower = k + 1; i > 0; --i) {
    while (k >= lower && turnOf(hull[k - 2], hull[k - 1], ends[i - 1]) <= 0) --k;
    hull[k++] = ends[i - 1];
  }
  hull.resize(k - 1);  // the last is the first again
  return extentOfHull(std::vector<cv::Point2d>(hull.begin(), hull.end()));
}

double boundaryLength(const std::vector<cv::Point>& closed) {
  const size_t n = closed.size();
  if (n < 2) return 0;
  int even = 0;
  int odd = 0;
  int corners = 0;
  int previous = -1;
  int first = -1;
  for (size_t i = 0; i < n; ++i) {
    const cv::Point d = closed[(i + 1) % n] - closed[i];
    // Chain code 0..7; even codes are axis steps, odd ones diagonal.
    static const int kCode[3][3] = {{3, 2, 1}, {4, -1, 0}, {5, 6, 7}};
    const int code = kCode[std::clamp(d.y, -1, 1) + 1][std::clamp(d.x, -1, 1) + 1];
    if (code < 0) continue;
    (code % 2 == 0 ? even : odd) += 1;
    if (previous >= 0 && code != previous) ++corners;
    if (first < 0) first = code;
    previous = code;
  }
  if (previous >= 0 && previous != first) ++corners;
  return 0.980 * even + 1.406 * odd - 0.091 * corners;
}

double eccentricity(const cv::Moments& m) {
  const double common = std::sqrt((m.mu20 - m.mu02) * (m.mu20 - m.mu02) + 4 * m.mu11 * m.mu11);
  const double major = m.mu20 + m.mu02 + common;
  const double minor = m.mu20 + m.mu02 - common;
  if (major <= 0) return 0;
  return std::sqrt(std::max(0.0, 1.0 - minor / major));
}

std::vector<double> radialSignature(const std::vector<cv::Point>& outer, cv::Point2d centroid,
                                    double start_deg, int samples) {
  std::vector<double> r(static_cast<size_t>(std::max(samples, 0)), -1.0);
  if (samples <= 0 || outer.empty()) return r;
  const double step = 360.0 / samples;
  for (const auto& p : outer) {
    const double dx = p.x - centroid.x;
    const double dy = p.y - centroid.y;
    const double a = normalizeDeg(std::atan2(dy, dx) * 180.0 / M_PI - start_deg + 0.5 * step);
    const size_t bin = std::min(static_cast<size_t>(a / step), r.size() - 1);
    r[bin] = std::max(r[bin], std::hypot(dx, dy));
  }
  // A small part has fewer boundary pixels than bins: empty bins take the
  // mean of their nearest filled neighbours.
  for (size_t i = 0; i < r.size(); ++i) {
    if (r[i] >= 0) continue;
    double before = -1;
    double after = -1;
    for (size_t k = 1; k < r.size() && (before < 0 || after < 0); ++k) {
      if (before < 0 && r[(i + r.size() - k) % r.size()] >= 0)
        before = r[(i + r.size() - k) % r.size()];
      if (after < 0 && r[(i + k) % r.size()] >= 0) after = r[(i + k) % r.size()];
    }
    r[i] = 0.5 * (std::max(before, 0.0) + std::max(after, 0.0));
  }
  return r;
}

cv::Mat skeletonize(const cv::Mat& mask) {
  CV_Assert(mask.type() == CV_8UC1);
  // A zero frame keeps every neighbourhood inside the image.
  cv::Mat img(mask.rows + 2, mask.cols + 2, CV_8UC1, cv::Scalar(0));
  cv::Mat inner = img(cv::Rect(1, 1, mask.cols, mask.rows));
  cv::compare(mask, 0, inner, cv::CMP_NE);
  img /= 255;
  std::vector<cv::Point> removal;
  for (bool changed = true; changed;) {
    changed = false;
    for (int pass = 0; pass < 2; ++pass) {
      removal.clear();
      for (int y = 1; y < img.rows - 1; ++y) {
        const uint8_t* up = img.ptr<uint8_t>(y - 1);
        const uint8_t* row = img.ptr<uint8_t>(y);
        const uint8_t* down = img.ptr<uint8_t>(y + 1);
        for (int x = 1; x < img.cols - 1; ++x) {
          if (!row[x]) continue;
          // Neighbours p2..p9 clockwise from north.
          const int p[8] = {up[x],   up[x + 1],   row[x + 1], down[x + 1],
                            down[x], down[x - 1], row[x - 1], up[x - 1]};
          int b = 0;
          int a = 0;
          for (int i = 0; i < 8; ++i) {
            b += p[i];
            a += (p[i] == 0 && p[(i + 1) % 8] == 1);
          }
          if (b < 2 || b > 6 || a != 1) continue;
          const bool keep = pass == 0 ? (p[0] * p[2] * p[4] != 0 || p[2] * p[4] * p[6] != 0)
                                      : (p[0] * p[2] * p[6] != 0 || p[0] * p[4] * p[6] != 0);
          if (!keep) removal.emplace_back(x, y);
        }
      }
      for (const auto& q : removal) img.at<uint8_t>(q) = 0;
      changed = changed || !removal.empty();
    }
  }
  cv::Mat out;
  img(cv::Rect(1, 1, mask.cols, mask.rows)).convertTo(out, CV_8U, 255);
  return out;
}

cv::Mat regionMask(const Region& region) {
  cv::Mat mask(region.bbox.size(), CV_8UC1, cv::Scalar(0));
  const cv::Point offset = -region.bbox.tl();
  cv::drawContours(mask, std::vector<std::vector<cv::Point>>{region.outer}, 0, cv::Scalar(255),
                   cv::FILLED, cv::LINE_8, cv::noArray(), INT_MAX, offset);
  // A hole's boundary pixels belong to the body: fill the hole, then redraw
  // its boundary.
  for (const auto& hole : region.hole_boundaries) {
    const std::vector<std::vector<cv::Point>> loops{hole};
    cv::drawContours(mask, loops, 0, cv::Scalar(0), cv::FILLED, cv::LINE_8, cv::noArray(), INT_MAX,
                     offset);
    cv::drawContours(mask, loops, 0, cv::Scalar(255), 1, cv::LINE_8, cv::noArray(), INT_MAX,
                     offset);
  }
  return mask;
}

namespace {
// sum_p C(k, p) S_p (i y)^(k-p) summed over the rows, S_p = sum_x w x^p of
// the row: k + 1 products and sums a pixel instead of a complex power. The
// order K a constant where it can be (the sums then stay in registers);
// K = -1: the order `k` known only at run time.
//
// x^p depends on the column only: the powers of every column and their
// running sums along the row are computed once, so a pixel of the band
// costs k + 1 products, and a run of fully covered pixels (most of a part)
// k + 1 differences whatever its length.
template <int K>
std::complex<double> rowPowerSums(const Region& region, int k, double scale) {
  using Sums =
      std::conditional_t<(K < 0), std::vector<double>, std::array<double, (K < 0 ? 1 : K + 1)>>;
  const int n = K < 0 ? k + 1 : K + 1;
  const int order = n - 1;
  Sums binomial{};
  if constexpr (K < 0) binomial.resize(static_cast<size_t>(n));
  binomial[0] = 1;
  for (int p = 1; p < n; ++p) binomial[p] = binomial[p - 1] * (order - p + 1) / p;
  const cv::Mat& w = region.coverage;
  const auto cols = static_cast<size_t>(w.cols);
  const auto un = static_cast<size_t>(n);
  // power[x n + p] = dx^p; before[x n + p] = the sum of dx^p over columns < x.
  std::vector<double> power(cols * un);
  std::vector<double> before((cols + 1) * un, 0.0);
  for (size_t x = 0; x < cols; ++x) {
    const double dx =
        (region.coverage_origin.x + static_cast<double>(x) - region.centroid.x) * scale;
    double term = 1;
    for (size_t p = 0; p < un; ++p) {
      power[x * un + p] = term;
      before[(x + 1) * un + p] = before[x * un + p] + term;
      term *= dx;
    }
  }
  // One row's power sums over the columns [a, b).
  const auto addSpan = [&](const float* row, size_t a, size_t b, Sums& sums) {
    for (size_t x = a; x < b;) {
      const float v = row[x];
      if (v <= 0) {
        ++x;
        continue;
      }
      if (v < 1.0f) {
        for (size_t p = 0; p < un; ++p) sums[p] += v * power[x * un + p];
        ++x;
        continue;
      }
      const size_t start = x;
      while (x < b && row[x] >= 1.0f) ++x;
      for (size_t p = 0; p < un; ++p) sums[p] += before[x * un + p] - before[start * un + p];
    }
  };
  // Horner in (i y): the p = 0 sum takes (i y)^k.
  std::complex<double> sum(0, 0);
  const auto addRow = [&](int y, const Sums& sums) {
    const std::complex<double> iy(0, (region.coverage_origin.y + y - region.centroid.y) * scale);
    std::complex<double> acc(0, 0);
    for (int p = 0; p < n; ++p) acc = acc * iy + binomial[p] * sums[p];
    sum += acc;
  };
  const auto emptySums = [&] {
    Sums sums{};
    if constexpr (K < 0) sums.resize(un);
    return sums;
  };
  if (region.covered.height() == w.rows && region.covered.width() == w.cols) {
    // Only where the coverage may be non-zero.
    int row_y = -1;
    Sums sums = emptySums();
    region.covered.forEachRun([&](int y, int a, int b) {
      if (y != row_y) {
        if (row_y >= 0) addRow(row_y, sums);
        row_y = y;
        sums = emptySums();
      }
      addSpan(w.ptr<float>(y), static_cast<size_t>(a), static_cast<size_t>(b), sums);
    });
    if (row_y >= 0) addRow(row_y, sums);
    return sum;
  }
  for (int y = 0; y < w.rows; ++y) {
    Sums sums = emptySums();
    addSpan(w.ptr<float>(y), 0, cols, sums);
    addRow(y, sums);
  }
  return sum;
}
}  // namespace

std::complex<double> complexMoment(const Region& region, int k) {
  const cv::Mat& w = region.coverage;
  if (w.empty() || region.area <= 0 || k < 0) return {0, 0};
  const double scale = 1.0 / std::sqrt(region.area);
  std::complex<double> sum;
  switch (k) {
    case 0:
      sum = rowPowerSums<0>(region, k, scale);
      break;
    case 1:
      sum = rowPowerSums<1>(region, k, scale);
      break;
    case 2:
      sum = rowPowerSums<2>(region, k, scale);
      break;
    case 3:
      sum = rowPowerSums<3>(region, k, scale);
      break;
    case 4:
      sum = rowPowerSums<4>(region, k, scale);
      break;
    case 5:
      sum = rowPowerSums<5>(region, k, scale);
      break;
    case 6:
      sum = rowPowerSums<6>(region, k, scale);
      break;
    case 7:
      sum = rowPowerSums<7>(region, k, scale);
      break;
    case 8:
      sum = rowPowerSums<8>(region, k, scale);
      break;
    case 9:
      sum = rowPowerSums<9>(region, k, scale);
      break;
    case 10:
      sum = rowPowerSums<10>(region, k, scale);
      break;
    case 11:
      sum = rowPowerSums<11>(region, k, scale);
      break;
    case 12:
      sum = rowPowerSums<12>(region, k, scale);
      break;
    default:
      sum = rowPowerSums<-1>(region, k, scale);
  }
  return sum * scale * scale;
}

BlobFeatures blobFeatures(const Region& region, const FeatureOptions& options) {
  BlobFeatures f;
  f.area = region.area;
  f.perimeter = boundaryLength(region.outer);
  f.roundness = f.perimeter > 0 ? 4 * M_PI * f.area / (f.perimeter * f.perimeter) : 0;
  f.holes = region.holes;
  f.eccentricity = eccentricity(region.moments);
  f.bbox = region.bbox;
  f.centroid = region.centroid;
  f.angle_deg = region.angle_deg;
  // Raw moments about the image origin from the central ones: exact, whatever
  // origin the region's own raw moments were taken about.
  cv::Moments m = region.moments;
  const double a = m.m00;
  const double cx = region.centroid.x;
  const double cy = region.centroid.y;
  m.m10 = a * cx;
  m.m01 = a * cy;
  m.m20 = m.mu20 + a * cx * cx;
  m.m11 = m.mu11 + a * cx * cy;
  m.m02 = m.mu02 + a * cy * cy;
  m.m30 = m.mu30 + 3 * cx * m.mu20 + a * cx * cx * cx;
  m.m21 = m.mu21 + 2 * cx * m.mu11 + cy * m.mu20 + a * cx * cx * cy;
  m.m12 = m.mu12 + 2 * cy * m.mu11 + cx * m.mu02 + a * cx * cy * cy;
  m.m03 = m.mu03 + 3 * cy * m.mu02 + a * cy * cy * cy;
  f.moments = m;
  f.hu = huInvariants(region.moments);
  f.log_hu = logHu(f.hu);
  f.radial_signature =
      radialSignature(region.outer, region.centroid, region.angle_deg, options.radial_samples);
  if (options.skeleton) {
    const cv::Mat skeleton = skeletonize(regionMask(region));
    std::vector<cv::Point> points;
    cv::findNonZero(skeleton, points);
    for (auto& p : points) p += region.bbox.tl();
    f.skeleton = std::move(points);
  }
  return f;
}

}  // namespace picksight::vision
