// Blob features against closed forms: a disc's roundness and Hu invariants, a
// rectangle's moments, an L shape's invariants under rotation and mirroring.
#include <catch2/catch.hpp>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "picksight/common/angles.hpp"
#include "picksight/vision/segmentation/blob_features.hpp"

using namespace picksight::vision;
using picksight::angleDiffDeg;

namespace {
constexpr int kSuper = 8;

// A dark polygon (50) on a light background (220), drawn 8x larger and
// averaged down so edge pixels are partly covered, as a camera sees them.
cv::Mat drawPolygon(const std::vector<cv::Point2d>& pts, cv::Size size) {
  std::vector<cv::Point> big;
  for (const auto& p : pts) {
    big.emplace_back(static_cast<int>(std::lround(((p.x + 0.5) * kSuper - 0.5) * 256)),
                     static_cast<int>(std::lround(((p.y + 0.5) * kSuper - 0.5) * 256)));
  }
  cv::Mat canvas(size * kSuper, CV_8UC1, cv::Scalar(0));
  cv::fillPoly(canvas, std::vector<std::vector<cv::Point>>{big}, cv::Scalar(255), cv::LINE_8, 8);
  cv::Mat coverage;
  cv::resize(canvas, coverage, size, 0, 0, cv::INTER_AREA);
  cv::Mat grey;
  coverage.convertTo(grey, CV_8U, -170.0 / 255.0, 220.0);
  return grey;
}

std::vector<cv::Point2d> discPolygon(cv::Point2d c, double r) {
  std::vector<cv::Point2d> pts;
  for (int i = 0; i < 720; ++i)
    pts.emplace_back(c.x + r * std::cos(i * M_PI / 360), c.y + r * std::sin(i * M_PI / 360));
  return pts;
}

std::vector<cv::Point2d> lPolygon(double deg, bool mirrored) {
  const std::vector<cv::Point2d> local = {{0, 0}, {120, 0}, {120, 30}, {30, 30}, {30, 70}, {0, 70}};
  std::vector<cv::Point2d> out;
  const double a = deg * M_PI / 180;
  for (auto p : local) {
    p -= cv::Point2d(45, 25);
    if (mirrored) p.y = -p.y;
    out.emplace_back(200 + p.x * std::cos(a) - p.y * std::sin(a),
                     200 + p.x * std::sin(a) + p.y * std::cos(a));
  }
  return out;
}

Region only(const cv::Mat& grey) {
  const auto regions = findRegions(grey < 135, {}, grey);
  REQUIRE(regions.size() == 1);
  return regions[0];
}
}  // namespace

TEST_CASE("a disc is round, not eccentric, and has the Hu invariants of a disc", "[vision][blob]") {
  const Region r = only(drawPolygon(discPolygon({150, 140}, 60), {300, 300}));
  const BlobFeatures f = blobFeatures(r);
  CHECK(f.area == Approx(M_PI * 60 * 60).epsilon(0.002));
  CHECK(f.roundness == Approx(1.0).epsilon(0.02));
  CHECK(f.eccentricity < 0.05);
  CHECK(f.holes == 0);
  // h1 = (nu20 + nu02) = 1 / (2 pi) for a disc; every other invariant is 0.
  CHECK(f.hu[0] == Approx(1 / (2 * M_PI)).epsilon(1e-3));
  for (int i = 1; i < 7; ++i) CHECK(std::abs(f.hu[i]) < 1e-6);
  CHECK(f.log_hu[0] == Approx(-std::log10(1 / (2 * M_PI))).epsilon(1e-3));
  REQUIRE(f.radial_signature.size() == 64);
  for (double d : f.radial_signature)
    CHECK(d == Approx(59.5).margin(1.0));  // boundary pixel centres
  CHECK(f.centroid.x == Approx(150).margin(0.02));
  CHECK(f.centroid.y == Approx(140).margin(0.02));
}

TEST_CASE("a rectangle's raw and central moments match the closed form", "[vision][blob]") {
  cv::Mat mask(100, 120, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(10, 20, 50, 20)).setTo(255);
  const auto regions = findRegions(mask);
  REQUIRE(regions.size() == 1);
  const BlobFeatures f = blobFeatures(regions[0]);
  // Sums over x = 10..59 and y = 20..39.
  double sx = 0, sxx = 0, sxxx = 0, sy = 0, syy = 0, syyy = 0;
  for (int x = 10; x < 60; ++x) sx += x, sxx += x * x, sxxx += 1.0 * x * x * x;
  for (int y = 20; y < 40; ++y) sy += y, syy += y * y, syyy += 1.0 * y * y * y;
  CHECK(f.moments.m00 == 1000);
  CHECK(f.moments.m10 == Approx(20 * sx));
  CHECK(f.moments.m01 == Approx(50 * sy));
  CHECK(f.moments.m20 == Approx(20 * sxx));
  CHECK(f.moments.m11 == Approx(sx * sy));
  CHECK(f.moments.m02 == Approx(50 * syy));
  CHECK(f.moments.m30 == Approx(20 * sxxx));
  CHECK(f.moments.m21 == Approx(sxx * sy));
  CHECK(f.moments.m03 == Approx(50 * syyy));
  CHECK(f.moments.mu20 == Approx(1000 * (50 * 50 - 1) / 12.0));
  CHECK(f.moments.mu02 == Approx(1000 * (20 * 20 - 1) / 12.0));
  CHECK(f.moments.mu30 == Approx(0).margin(1e-6));
  CHECK(f.eccentricity == Approx(std::sqrt(1 - 399.0 / 2499.0)));
  // h1 = nu20 + nu02, h2 = (nu20 - nu02)^2 for an axis-aligned rectangle.
  const double nu20 = f.moments.mu20 / 1e6;
  const double nu02 = f.moments.mu02 / 1e6;
  CHECK(f.hu[0] == Approx(nu20 + nu02));
  CHECK(f.hu[1] == Approx((nu20 - nu02) * (nu20 - nu02)));
  CHECK(f.bbox == cv::Rect(10, 20, 50, 20));
  // The boundary through the edge pixel centres is 2 * (49 + 19) long.
  CHECK(f.perimeter == Approx(136).epsilon(0.03));
  CHECK(f.roundness == Approx(4 * M_PI * 1000 / (f.perimeter * f.perimeter)));
}

TEST_CASE("the perimeter estimate holds at any angle", "[vision][blob]") {
  for (double deg : {0.0, 10.0, 30.0, 45.0}) {
    INFO(deg);
    const Region r = only(drawPolygon(lPolygon(deg, false), {400, 400}));
    // True length 2 * (120 + 70) = 380, less the half pixel the boundary
    // pixel centres sit inside the edge at 5 convex and 1 concave corner.
    CHECK(blobFeatures(r).perimeter == Approx(380 - 4).epsilon(0.03));
  }
}

TEST_CASE("an L shape's log Hu invariants survive rotation and the 7th changes sign in a mirror",
          "[vision][blob]") {
  const BlobFeatures base = blobFeatures(only(drawPolygon(lPolygon(0, false), {400, 400})));
  for (double deg : {33.0, 90.0, 161.0, 270.0}) {
    INFO(deg);
    const BlobFeatures turned = blobFeatures(only(drawPolygon(lPolygon(deg, false), {400, 400})));
    const BlobFeatures mirrored = blobFeatures(only(drawPolygon(lPolygon(deg, true), {400, 400})));
    for (int i = 0; i < 6; ++i) {
      CHECK(turned.log_hu[i] == Approx(base.log_hu[i]).epsilon(0.01));
      CHECK(mirrored.log_hu[i] == Approx(base.log_hu[i]).epsilon(0.01));
    }
    CHECK(turned.log_hu[6] == Approx(base.log_hu[6]).epsilon(0.01));
    CHECK(mirrored.log_hu[6] == Approx(-base.log_hu[6]).epsilon(0.01));
    CHECK(angleDiffDeg(turned.angle_deg, base.angle_deg + deg) < 0.1);
    CHECK(angleDiffDeg(mirrored.angle_deg, -base.angle_deg + deg) < 0.1);
  }
}

TEST_CASE("complex moments turn k times as fast as the part", "[vision][blob]") {
  const Region base = only(drawPolygon(lPolygon(0, false), {400, 400}));
  const Region turned = only(drawPolygon(lPolygon(40, false), {400, 400}));
  for (int k : {2, 3, 5}) {
    INFO(k);
    const double a0 = std::arg(complexMoment(base, k)) * 180 / M_PI;
    const double a1 = std::arg(complexMoment(turned, k)) * 180 / M_PI;
    CHECK(angleDiffDeg(a1 - a0, k * 40.0) < 0.2 * k);
    CHECK(std::abs(complexMoment(turned, k)) ==
          Approx(std::abs(complexMoment(base, k))).epsilon(0.01));
  }
}

TEST_CASE("the skeleton of a bar is its middle line", "[vision][blob]") {
  cv::Mat mask(60, 200, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(20, 25, 150, 9)).setTo(255);
  const auto regions = findRegions(mask);
  REQUIRE(regions.size() == 1);
  const BlobFeatures f = blobFeatures(regions[0]);
  REQUIRE(f.skeleton.size() > 130);
  int min_x = 1000, max_x = 0;
  for (const auto& p : f.skeleton) {
    CHECK(std::abs(p.y - 29) <= 1);
    min_x = std::min(min_x, p.x);
    max_x = std::max(max_x, p.x);
  }
  CHECK(max_x - min_x > 130);
  CHECK(f.skeleton.size() < 160);  // one pixel wide
}

TEST_CASE("a shape's extent is its length and its narrowest width at any turn", "[vision][blob]") {
  // A 100 x 40 rectangle with a notch (the hull closes it), and points
  // inside that change nothing, turned by several angles.
  const std::vector<cv::Point2d> shape = {{0, 0},   {100, 0}, {100, 40}, {60, 40},
                                          {50, 20}, {40, 40}, {0, 40},   {30, 10}};
  for (const double turn : {0.0, 17.0, 30.0, 90.0, 143.0}) {
    CAPTURE(turn);
    const double c = std::cos(turn * picksight::kRadPerDeg);
    const double s = std::sin(turn * picksight::kRadPerDeg);
    std::vector<cv::Point2f> points;
    for (const auto& p : shape) {
      points.emplace_back(static_cast<float>(500 + c * p.x - s * p.y),
                          static_cast<float>(300 + s * p.x + c * p.y));
    }
    const Extent e = extentOf(points);
    CHECK(e.diameter == Approx(std::hypot(100.0, 40.0)).margin(1e-3));
    CHECK(e.width == Approx(40.0).margin(1e-3));
  }
  // A disc's width is its diameter; a segment has no width; a point nothing.
  std::vector<cv::Point2f> disc;
  for (int k = 0; k < 360; ++k) {
    disc.emplace_back(static_cast<float>(50 * std::cos(k * picksight::kRadPerDeg)),
                      static_cast<float>(50 * std::sin(k * picksight::kRadPerDeg)));
  }
  const Extent round = extentOf(disc);
  CHECK(round.diameter == Approx(100.0).margin(0.01));
  CHECK(round.width == Approx(100.0).margin(0.05));
  const Extent segment = extentOf({{0, 0}, {30, 40}});
  CHECK(segment.diameter == Approx(50.0));
  CHECK(segment.width == 0);
  CHECK(extentOf({{3, 4}}).diameter == 0);
}

TEST_CASE("a shape's extent is that of every pair of its hull's points", "[vision][blob]") {
  // Random clouds, round and long, and pixel outlines (many points in a row,
  // parallel edges): the one-pass calipers against every pair.
  cv::RNG rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    CAPTURE(trial);
    std::vector<cv::Point2f> points;
    const int count = 3 + trial % 40;
    const double stretch = 1 + trial % 5;
    for (int k = 0; k < count; ++k) {
      const double x = rng.uniform(-50.0, 50.0) * stretch;
      const double y = rng.uniform(-50.0, 50.0);
      // Every third cloud on the pixel grid.
      points.emplace_back(trial % 3 == 0 ? std::round(x) : x, trial % 3 == 0 ? std::round(y) : y);
    }
    std::vector<cv::Point2f> hull;
    cv::convexHull(points, hull);
    double diameter = 0;
    double width = hull.size() < 3 ? 0 : 1e300;
    for (size_t i = 0; i < hull.size(); ++i) {
      const cv::Point2d a = hull[i];
      const cv::Point2d b = hull[(i + 1) % hull.size()];
      double farthest = 0;
      for (const cv::Point2d p : hull) {
        diameter = std::max(diameter, cv::norm(p - a));
        farthest = std::max(farthest, std::abs((b - a).cross(p - a)) / cv::norm(b - a));
      }
      if (hull.size() >= 3) width = std::min(width, farthest);
    }
    const Extent e = extentOf(points);
    CHECK(e.diameter == Approx(diameter).margin(1e-9));
    CHECK(e.width == Approx(width).margin(1e-9));
  }
}

TEST_CASE("an outline's extent is its points' to the last digit", "[vision][blob]") {
  // The outlines of random pixel sets (discs, bars, lines, specks, some
  // cut by the box's edge; rows with one pixel, columns of one): read from
  // the rows' ends, the figures those of every point's hull.
  cv::RNG rng(41);
  int outlines = 0;
  for (int trial = 0; trial < 80; ++trial) {
    cv::Mat mask(120, 160, CV_8UC1, cv::Scalar(0));
    for (int k = 0; k < 6; ++k) {
      const cv::Point p(rng.uniform(-10, 170), rng.uniform(-10, 130));
      switch (rng.uniform(0, 4)) {
        case 0:
          cv::circle(mask, p, rng.uniform(1, 40), cv::Scalar(255), cv::FILLED);
          break;
        case 1:
          cv::line(mask, p, {rng.uniform(-10, 170), rng.uniform(-10, 130)}, cv::Scalar(255),
                   rng.uniform(1, 4));
          break;
        case 2:
          cv::ellipse(mask, p, {rng.uniform(1, 50), rng.uniform(1, 10)}, rng.uniform(0.0, 180.0), 0,
                      360, cv::Scalar(255), cv::FILLED);
          break;
        default:
          mask.at<uint8_t>(std::clamp(p.y, 0, 119), std::clamp(p.x, 0, 159)) = 255;
          break;
      }
    }
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(mask, contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE);
    for (const auto& outline : contours) {
      CAPTURE(trial, outline.size());
      const Extent rows = extentOfOutline(outline);
      const Extent points = extentOf(std::vector<cv::Point2f>(outline.begin(), outline.end()));
      CHECK(rows.diameter == points.diameter);
      CHECK(rows.width == points.width);
      ++outlines;
    }
  }
  CHECK(outlines > 300);
  CHECK(extentOfOutline({{3, 4}}).diameter == 0);
  CHECK(extentOfOutline({{0, 0}, {30, 40}}).diameter == 50);
}
