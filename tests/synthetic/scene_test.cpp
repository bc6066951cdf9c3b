// Tests of the synthetic scene generator: exact truth, unbiased rendering, placement, noise.
#include "picksight/synthetic/scene.hpp"

#include "picksight/synthetic/front_light.hpp"
#include "picksight/synthetic/silhouette_scene.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include "picksight/codecs/codecs.hpp"

namespace ps = picksight::synthetic;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kBackground = 200;
constexpr double kPart = 45;

double boundingRadius(const ps::Shape& shape) {
  double r = 0;
  for (const cv::Point2d& p : shape.loops.at(0)) {
    r = std::max(r, std::hypot(p.x, p.y));
  }
  return r;
}

// Signed difference folded into (-period/2, period/2].
double angleError(double measured_deg, double truth_deg, double period_deg) {
  double d = std::fmod(measured_deg - truth_deg, period_deg);
  if (d > period_deg / 2) {
    d -= period_deg;
  }
  if (d <= -period_deg / 2) {
    d += period_deg;
  }
  return d;
}

ps::SceneOptions flatScene(std::vector<std::string> types, uint64_t seed, int parts = 12) {
  ps::SceneOptions o = ps::sceneOptions(1280, 960, parts, seed, std::move(types));
  o.noise_sigma = 0;
  o.uneven_light = false;
  o.background_level = kBackground;
  o.part_level = kPart;
  return o;
}

// What a vision app would measure on one part, from the pixels within its
// bounding circle + 3 px (coverage reaches 1 px past the polygon; other parts
// are kept 8 px further away).
struct Measured {
  double cx = 0;  // grey-level weighted, weights background - pixel
  double cy = 0;
  double area = 0;           // sum of coverage (background - pixel) / contrast
  double grey_axis_deg = 0;  // axis of the grey-level weights, (-90, 90]
  double angle_deg = 0;      // binary: threshold at mid-level, cv::moments, longer reach forward
  double hu7 = 0;            // of the grey-level weights
};

Measured measurePart(const cv::Mat& image, const ps::PartTruth& t, double radius) {
  const double r = radius + 3;
  const cv::Rect roi =
      cv::Rect(static_cast<int>(std::floor(t.x - r)), static_cast<int>(std::floor(t.y - r)),
               static_cast<int>(2 * r + 2), static_cast<int>(2 * r + 2)) &
      cv::Rect(0, 0, image.cols, image.rows);
  cv::Mat weights(roi.size(), CV_64F, cv::Scalar(0));
  cv::Mat mask(roi.size(), CV_8U, cv::Scalar(0));
  double sw = 0, swx = 0, swy = 0;
  for (int v = 0; v < roi.height; ++v) {
    for (int u = 0; u < roi.width; ++u) {
      const int x = roi.x + u;
      const int y = roi.y + v;
      if (std::hypot(x - t.x, y - t.y) > r) {
        continue;
      }
      const double pixel = image.at<uint8_t>(y, x);
      const double w = kBackground - pixel;
      weights.at<double>(v, u) = w;
      sw += w;
      swx += w * x;
      swy += w * y;
      if (pixel < (kBackground + kPart) / 2) {
        mask.at<uint8_t>(v, u) = 1;
      }
    }
  }
  Measured m;
  m.cx = swx / sw;
  m.cy = swy / sw;
  m.area = sw / (kBackground - kPart);

  const cv::Moments bm = cv::moments(mask, true);
  double theta = 0.5 * std::atan2(2 * bm.mu11, bm.mu20 - bm.mu02);
  const double bx = bm.m10 / bm.m00;
  const double by = bm.m01 / bm.m00;
  double fwd = -1e9, back = 1e9;
  for (int v = 0; v < mask.rows; ++v) {
    for (int u = 0; u < mask.cols; ++u) {
      if (!mask.at<uint8_t>(v, u)) {
        continue;
      }
      const double p = (u - bx) * std::cos(theta) + (v - by) * std::sin(theta);
      fwd = std::max(fwd, p);
      back = std::min(back, p);
    }
  }
  if (-back > fwd) {
    theta += kPi;
  }
  m.angle_deg = std::fmod(theta * 180 / kPi + 720, 360);

  const cv::Moments gm = cv::moments(weights, false);
  m.grey_axis_deg = 0.5 * std::atan2(2 * gm.mu11, gm.mu20 - gm.mu02) * 180 / kPi;
  double hu[7];
  cv::HuMoments(gm, hu);
  m.hu7 = hu[6];
  return m;
}

std::vector<std::pair<double, double>> sortedPoints(const ps::Shape& shape) {
  std::vector<std::pair<double, double>> pts;
  for (const auto& loop : shape.loops) {
    for (const cv::Point2d& p : loop) {
      pts.emplace_back(p.x, p.y);
    }
  }
  std::sort(pts.begin(), pts.end());
  return pts;
}

}  // namespace

TEST_CASE("shapeMoments of rectangles match the closed form", "[synthetic]") {
  const double w = 10, h = 4, x0 = 3, y0 = -2;
  const ps::Shape ccw{{{{x0, y0}, {x0 + w, y0}, {x0 + w, y0 + h}, {x0, y0 + h}}}};
  const ps::Shape cw{{{{x0, y0}, {x0, y0 + h}, {x0 + w, y0 + h}, {x0 + w, y0}}}};
  for (const ps::Shape& s : {ccw, cw}) {
    const ps::ShapeMoments m = ps::shapeMoments(s);
    CHECK(m.area == Approx(w * h));
    CHECK(ps::shapeArea(s) == Approx(w * h));
    CHECK(m.cx == Approx(x0 + w / 2));
    CHECK(m.cy == Approx(y0 + h / 2).margin(1e-12));
    CHECK(m.mu20 == Approx(w * w * w * h / 12));
    CHECK(m.mu02 == Approx(w * h * h * h / 12));
    CHECK(m.mu11 == Approx(0).margin(1e-9));
  }

  SECTION("a hole is subtracted whatever its winding") {
    // Outer [0,10]x[0,4], hole [1,3]x[1,2]: parallel-axis composition.
    const double hw = 2, hh = 1, hx = 2, hy = 1.5;
    const double area = w * h - hw * hh;
    const double cx = (w * h * 5 - hw * hh * hx) / area;
    const double cy = (w * h * 2 - hw * hh * hy) / area;
    const double mu20 = w * w * w * h / 12 + w * h * (5 - cx) * (5 - cx) -
                        (hw * hw * hw * hh / 12 + hw * hh * (hx - cx) * (hx - cx));
    const double mu02 = w * h * h * h / 12 + w * h * (2 - cy) * (2 - cy) -
                        (hw * hh * hh * hh / 12 + hw * hh * (hy - cy) * (hy - cy));
    const double mu11 = w * h * (5 - cx) * (2 - cy) - hw * hh * (hx - cx) * (hy - cy);
    const std::vector<cv::Point2d> outer{{0, 0}, {10, 0}, {10, 4}, {0, 4}};
    std::vector<cv::Point2d> hole{{1, 1}, {3, 1}, {3, 2}, {1, 2}};
    for (int winding = 0; winding < 2; ++winding) {
      if (winding) {
        std::reverse(hole.begin(), hole.end());
      }
      const ps::ShapeMoments m = ps::shapeMoments(ps::Shape{{outer, hole}});
      CHECK(m.area == Approx(area));
      CHECK(m.cx == Approx(cx));
      CHECK(m.cy == Approx(cy));
      CHECK(m.mu20 == Approx(mu20));
      CHECK(m.mu02 == Approx(mu02));
      CHECK(m.mu11 == Approx(mu11));
    }
  }

  SECTION("a rotated rectangle far from the origin") {
    const double a = 30 * kPi / 180, c = std::cos(a), s = std::sin(a);
    const ps::Shape centred{{{{-w / 2, -h / 2}, {w / 2, -h / 2}, {w / 2, h / 2}, {-w / 2, h / 2}}}};
    const ps::ShapeMoments m = ps::shapeMoments(ps::placedShape(centred, 1500.25, 900.75, 30));
    const double mu20 = w * w * w * h / 12, mu02 = w * h * h * h / 12;
    CHECK(m.area == Approx(w * h));
    CHECK(m.cx == Approx(1500.25).epsilon(1e-12));
    CHECK(m.cy == Approx(900.75).epsilon(1e-12));
    CHECK(m.mu20 == Approx(c * c * mu20 + s * s * mu02).epsilon(1e-9));
    CHECK(m.mu02 == Approx(s * s * mu20 + c * c * mu02).epsilon(1e-9));
    CHECK(m.mu11 == Approx(c * s * (mu20 - mu02)).epsilon(1e-9));
  }
}

TEST_CASE(
    "canonical part shapes: centroid at origin, least-inertia axis on +x, longer reach forward",
    "[synthetic]") {
  const double size = 120;
  for (const std::string& type : ps::partTypes()) {
    INFO(type);
    const ps::Shape shape = ps::partShape(type, size);
    const ps::ShapeMoments m = ps::shapeMoments(shape);
    const double scale = m.mu20 + m.mu02;
    CHECK(std::abs(m.cx) < 1e-9 * size);
    CHECK(std::abs(m.cy) < 1e-9 * size);
    CHECK(std::abs(m.mu11) < 1e-12 * scale);
    if (ps::angleSymmetryDeg(shape) != 0) {
      CHECK(m.mu20 > m.mu02);
      double fwd = 0, back = 0;
      for (const cv::Point2d& p : shape.loops[0]) {
        fwd = std::max(fwd, p.x);
        back = std::max(back, -p.x);
      }
      CHECK(fwd >= back);
    }
    // Outer loop positive (shoelace in image axes), holes negative.
    for (std::size_t k = 0; k < shape.loops.size(); ++k) {
      const ps::ShapeMoments lm = ps::shapeMoments(ps::Shape{{shape.loops[k]}});
      double twice = 0;
      const auto& l = shape.loops[k];
      for (std::size_t i = 0; i < l.size(); ++i) {
        twice += l[i].x * l[(i + 1) % l.size()].y - l[(i + 1) % l.size()].x * l[i].y;
      }
      CHECK((twice > 0) == (k == 0));
      CHECK(lm.area > 0);
    }
  }

  CHECK(ps::angleSymmetryDeg(ps::partShape("rectangle", size)) == 180);
  CHECK(ps::angleSymmetryDeg(ps::partShape("l_shape", size)) == 360);
  CHECK(ps::angleSymmetryDeg(ps::partShape("l_shape_mirror", size)) == 360);
  CHECK(ps::angleSymmetryDeg(ps::partShape("disc_holes", size)) == 360);
  CHECK(ps::angleSymmetryDeg(ps::partShape("gear", size)) == 0);
  // A square's inertia is isotropic although the square is not round.
  CHECK(ps::angleSymmetryDeg(ps::Shape{{{{0, 0}, {5, 0}, {5, 5}, {0, 5}}}}) == 0);

  CHECK(ps::shapeArea(ps::partShape("rectangle", size)) == Approx(size * size / 2.1));
  CHECK(ps::shapeArea(ps::partShape("l_shape", size)) == Approx(0.39 * size * size));
  CHECK(ps::shapeArea(ps::partShape("l_shape_mirror", size)) == Approx(0.39 * size * size));
  const double r = size / 2;
  CHECK(ps::shapeArea(ps::partShape("disc_holes", size)) ==
        Approx(kPi * r * r * (1 - 0.45 * 0.45 - 0.34 * 0.34)).epsilon(2e-3));

  SECTION("the longest side is `size`") {
    for (const std::string& type : ps::partTypes()) {
      INFO(type);
      const ps::Shape shape = ps::partShape(type, size);
      if (type == "disc_holes" || type == "gear") {
        double diameter = 0;  // largest distance between two outer vertices
        for (const cv::Point2d& a : shape.loops[0]) {
          for (const cv::Point2d& b : shape.loops[0]) {
            diameter = std::max(diameter, cv::norm(a - b));
          }
        }
        CHECK(diameter == Approx(size));
      } else {
        std::vector<cv::Point2f> pts;
        for (const cv::Point2d& p : shape.loops[0]) {
          pts.emplace_back(p);
        }
        const cv::RotatedRect box = cv::minAreaRect(pts);
        CHECK(std::max(box.size.width, box.size.height) == Approx(size).epsilon(1e-5));
      }
    }
  }

  SECTION("areas tell the types apart, except a part from its mirror image") {
    const auto& types = ps::partTypes();
    for (std::size_t i = 0; i < types.size(); ++i) {
      for (std::size_t j = i + 1; j < types.size(); ++j) {
        if (types[i].rfind("l_shape", 0) == 0 && types[j].rfind("l_shape", 0) == 0) {
          continue;
        }
        const double a = ps::shapeArea(ps::partShape(types[i], size));
        const double b = ps::shapeArea(ps::partShape(types[j], size));
        INFO(types[i] << " vs " << types[j]);
        CHECK(std::abs(a - b) > 0.08 * std::max(a, b));
      }
    }
  }

  SECTION("l_shape_mirror is l_shape reflected about its axis") {
    ps::Shape mirrored = ps::partShape("l_shape", size);
    for (auto& loop : mirrored.loops) {
      for (cv::Point2d& p : loop) {
        p.y = -p.y;
      }
    }
    const auto a = sortedPoints(mirrored);
    const auto b = sortedPoints(ps::partShape("l_shape_mirror", size));
    REQUIRE(a.size() == b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      CHECK(a[i].first == Approx(b[i].first).margin(1e-9));
      CHECK(a[i].second == Approx(b[i].second).margin(1e-9));
    }
  }

  SECTION("unknown types are rejected") {
    CHECK_THROWS_AS(ps::partShape("hexagon", size), std::invalid_argument);
    CHECK_THROWS_AS(ps::SceneRenderer(flatScene({"hexagon"}, 1)), std::invalid_argument);
  }
}

TEST_CASE("rendered parts: grey-level centroid, coverage area and angles match the truth",
          "[synthetic]") {
  for (const std::string& type : ps::partTypes()) {
    double worst_centroid = 0, worst_area = 0, worst_grey_axis = 0, worst_binary_angle = 0;
    for (uint64_t seed : {1u, 2u}) {
      const ps::SceneRenderer scene(flatScene({type}, seed));
      const double radius = boundingRadius(ps::partShape(type, scene.options().part_size));
      REQUIRE(scene.truth().size() == 12);
      for (const ps::PartTruth& t : scene.truth()) {
        CHECK(t.type == type);
        const Measured m = measurePart(scene.clean(), t, radius);
        worst_centroid = std::max(worst_centroid, std::hypot(m.cx - t.x, m.cy - t.y));
        worst_area = std::max(worst_area, std::abs(m.area - t.area_px) / t.area_px);
        if (t.symmetry_deg != 0) {
          worst_grey_axis =
              std::max(worst_grey_axis, std::abs(angleError(m.grey_axis_deg, t.angle_deg, 180)));
          worst_binary_angle = std::max(
              worst_binary_angle, std::abs(angleError(m.angle_deg, t.angle_deg, t.symmetry_deg)));
        }
      }
    }
    INFO(type);
    // Coverage is exact, so what is left is the 8-bit rounding and the
    // pixel-centre discretization of the moments: ~0.002 px, 0.005%, 0.004 deg.
    CHECK(worst_centroid < 0.02);  // px
    CHECK(worst_area < 0.005);
    CHECK(worst_grey_axis < 0.02);  // deg
    // Thresholding turns edges within a degree of a pixel axis into a single
    // step, which moves the binary axis by up to ~0.6 deg at 120 px whatever
    // the renderer does (seen on the rectangle at 89.9 deg and the L at 255.1
    // deg); the direction along the axis must still be right.
    CHECK(worst_binary_angle < 1.0);
  }
}

TEST_CASE("l_shape and l_shape_mirror render as mirror images", "[synthetic]") {
  const ps::SceneRenderer scene(flatScene({"l_shape", "l_shape_mirror"}, 7, 16));
  const double radius = boundingRadius(ps::partShape("l_shape", scene.options().part_size));
  // The 7th Hu invariant changes sign under reflection only: one sign for
  // every l_shape, whatever its pose, and the other for every mirror.
  int l_sign = 0, mirror_sign = 0;
  for (const ps::PartTruth& t : scene.truth()) {
    INFO(t.type << " at " << t.x << ", " << t.y << ", " << t.angle_deg << " deg");
    const Measured m = measurePart(scene.clean(), t, radius);
    const int sign = m.hu7 > 0 ? 1 : -1;
    int& expected = t.type == "l_shape" ? l_sign : mirror_sign;
    if (expected == 0) {
      expected = sign;
    }
    CHECK(sign == expected);
  }
  CHECK(l_sign != 0);
  CHECK(l_sign == -mirror_sign);
}

TEST_CASE("uneven light darkens background and parts alike", "[synthetic]") {
  ps::SceneOptions o = flatScene({"rectangle"}, 3, 8);
  o.uneven_light = true;
  const ps::SceneRenderer scene(o);
  double lo = 255, hi = 0;
  cv::minMaxLoc(scene.clean().row(0), &lo, &hi);
  CHECK(hi - lo > 10);  // a visible gradient along the top row
  CHECK(hi < 255);
  const double radius = boundingRadius(ps::partShape("rectangle", scene.options().part_size));
  for (const ps::PartTruth& t : scene.truth()) {
    // The rectangle's centre is inside it; a point just outside its bounding
    // circle is background under nearly the same light.
    const double inside = scene.clean().at<uint8_t>(cvRound(t.y), cvRound(t.x));
    const double outside = scene.clean().at<uint8_t>(cvRound(t.y), cvRound(t.x + radius + 3));
    CHECK(inside / outside == Approx(kPart / kBackground).epsilon(0.04));
  }
  // Same seed, same layout: light does not consume layout randomness.
  const ps::SceneRenderer flat(flatScene({"rectangle"}, 3, 8));
  REQUIRE(flat.truth().size() == scene.truth().size());
  for (std::size_t i = 0; i < flat.truth().size(); ++i) {
    CHECK(flat.truth()[i].x == scene.truth()[i].x);
    CHECK(flat.truth()[i].angle_deg == scene.truth()[i].angle_deg);
  }
}

namespace {

void checkPlacement(const ps::SceneRenderer& scene) {
  const ps::SceneOptions& o = scene.options();
  const auto& truth = scene.truth();
  REQUIRE(static_cast<int>(truth.size()) == o.parts);
  std::vector<double> radius;
  for (const ps::PartTruth& t : truth) {
    const ps::Shape shape = ps::partShape(t.type, o.part_size);
    radius.push_back(boundingRadius(shape));
    CHECK(t.area_px == Approx(ps::shapeArea(shape)));
    CHECK(t.angle_deg >= 0);
    CHECK(t.angle_deg < 360);
    const ps::Shape placed = ps::placedShape(shape, t.x, t.y, t.angle_deg);
    for (const cv::Point2d& p : placed.loops[0]) {
      // At least 1 px of background between any part and the border.
      CHECK(p.x > 0.5);
      CHECK(p.y > 0.5);
      CHECK(p.x < o.width - 1.5);
      CHECK(p.y < o.height - 1.5);
    }
  }
  for (std::size_t i = 0; i < truth.size(); ++i) {
    for (std::size_t j = i + 1; j < truth.size(); ++j) {
      CHECK(std::hypot(truth[i].x - truth[j].x, truth[i].y - truth[j].y) >
            radius[i] + radius[j] + 2);
    }
  }
}

}  // namespace

TEST_CASE("placement keeps parts apart and inside the image", "[synthetic]") {
  ps::SceneOptions o = flatScene({}, 11, 20);
  o.width = 1920;
  o.height = 1080;
  const ps::SceneRenderer scene(o);
  CHECK(scene.options().part_size == 120);
  checkPlacement(scene);
  for (const std::string& type : ps::partTypes()) {
    CHECK(std::count_if(scene.truth().begin(), scene.truth().end(),
                        [&](const ps::PartTruth& t) { return t.type == type; }) == 4);
  }
  // No ink on the border rows and columns.
  const cv::Mat& img = scene.clean();
  for (const cv::Mat& edge :
       {img.row(0), img.row(img.rows - 1), img.col(0), img.col(img.cols - 1)}) {
    CHECK(cv::countNonZero(edge != kBackground) == 0);
  }
}

TEST_CASE("crowded scenes shrink the parts instead of failing", "[synthetic]") {
  ps::SceneOptions o = flatScene({}, 5, 30);
  o.width = 640;
  o.height = 480;
  o.part_size = 200;
  const ps::SceneRenderer scene(o);
  CHECK(scene.options().part_size < 200);
  CHECK(scene.options().part_size > 20);
  checkPlacement(scene);

  ps::SceneOptions impossible = o;
  impossible.parts = 100000;
  CHECK_THROWS_AS(ps::SceneRenderer(impossible), std::invalid_argument);
}

TEST_CASE("layout is reproducible from the seed", "[synthetic]") {
  const ps::SceneRenderer a(flatScene({}, 42));
  const ps::SceneRenderer b(flatScene({}, 42));
  const ps::SceneRenderer c(flatScene({}, 43));
  REQUIRE(a.truth().size() == b.truth().size());
  for (std::size_t i = 0; i < a.truth().size(); ++i) {
    CHECK(a.truth()[i].type == b.truth()[i].type);
    CHECK(a.truth()[i].x == b.truth()[i].x);
    CHECK(a.truth()[i].y == b.truth()[i].y);
    CHECK(a.truth()[i].angle_deg == b.truth()[i].angle_deg);
  }
  CHECK(cv::norm(a.clean(), b.clean(), cv::NORM_INF) == 0);
  CHECK(a.truth()[0].x != c.truth()[0].x);
  CHECK(cv::norm(a.clean(), c.clean(), cv::NORM_INF) > 0);
}

TEST_CASE("render adds reproducible per-frame noise", "[synthetic]") {
  ps::SceneOptions o = flatScene({}, 9, 8);
  o.noise_sigma = 3;
  const ps::SceneRenderer scene(o);
  cv::Mat clean16;
  scene.clean().convertTo(clean16, CV_16S);
  auto noiseOf = [&](uint64_t i) {
    cv::Mat frame16;
    scene.render(i).convertTo(frame16, CV_16S);
    cv::Mat noise;
    cv::subtract(frame16, clean16, noise, cv::noArray(), CV_32F);
    return noise;
  };

  CHECK(cv::norm(scene.render(5), scene.render(5), cv::NORM_INF) == 0);
  const cv::Mat n5 = noiseOf(5);
  for (uint64_t i : {0u, 1u, 6u, 1000u}) {
    INFO("frame " << i);
    const cv::Mat n = noiseOf(i);
    cv::Scalar mean, stddev;
    cv::meanStdDev(n, mean, stddev);
    // Integer noise: sqrt(3^2 + 1/12) = 3.014 expected.
    CHECK(stddev[0] == Approx(3.0).epsilon(0.03));
    CHECK(std::abs(mean[0]) < 0.05);
    // Frames differ, and their noise is uncorrelated.
    const double correlation = n.dot(n5) / (cv::norm(n) * cv::norm(n5));
    CHECK(std::abs(correlation) < 0.05);
  }

  SECTION("renderInto reuses the buffer and never writes through a view of clean()") {
    cv::Mat out = scene.clean();
    const cv::Mat before = scene.clean().clone();
    scene.renderInto(3, out);
    CHECK(cv::norm(scene.clean(), before, cv::NORM_INF) == 0);
    CHECK(cv::norm(out, scene.render(3), cv::NORM_INF) == 0);
    const uint8_t* data = out.data;
    scene.renderInto(4, out);
    CHECK(out.data == data);
  }

  SECTION("noise_sigma 0 gives the clean image") {
    o.noise_sigma = 0;
    const ps::SceneRenderer quiet(o);
    CHECK(cv::norm(quiet.render(17), quiet.clean(), cv::NORM_INF) == 0);
  }
}

TEST_CASE("a photographed surface keeps the photograph's pattern at the condition's strength",
          "[synthetic][front]") {
  const cv::Mat photo = picksight::codecs::imread(
      std::string(PICKSIGHT_TEST_DATA_DIR) + "/surfaces/brick.png", cv::IMREAD_GRAYSCALE);
  REQUIRE(!photo.empty());
  ps::FrontLight light;
  double part = 0;
  double background = 0;
  CHECK_FALSE(ps::photographedCondition("marble", photo, &light, &part, &background));
  CHECK_FALSE(ps::photographedCondition("brick", cv::Mat(), &light, &part, &background));
  REQUIRE(ps::photographedCondition("brick", photo, &light, &part, &background));
  CHECK(light.surface == ps::Surface::kPhotographed);
  CHECK(background - part == 30);
  // Wider and taller than the photograph: mirrored at its borders.
  const cv::Size size(3 * photo.cols / 2, 3 * photo.rows / 2);
  const cv::Mat t =
      ps::detail::surfaceTexture(size, light.surface, light.texture, 5, light.surface_photo);
  REQUIRE(t.size() == size);
  cv::Scalar mean;
  cv::Scalar sd;
  cv::meanStdDev(t, mean, sd);
  CHECK(mean[0] == Approx(1).margin(1e-3));
  CHECK(sd[0] == Approx(light.texture).epsilon(0.02));
  const auto correlation = [](const cv::Mat& a, const cv::Mat& b) {
    cv::Mat fa;
    cv::Mat fb;
    a.convertTo(fa, CV_64F);
    b.convertTo(fb, CV_64F);
    fa -= cv::mean(fa);
    fb -= cv::mean(fb);
    return fa.dot(fb) / std::sqrt(fa.dot(fa) * fb.dot(fb));
  };
  // Both far corners of the texture are found in the photograph, mirrored
  // or not (0.99 unless a corner spans a mirrored seam).
  const auto inPhoto = [&photo](const cv::Mat& patch) {
    double best = 0;
    for (int flip_x = 0; flip_x < 2; ++flip_x) {
      for (int flip_y = 0; flip_y < 2; ++flip_y) {
        cv::Mat seen;
        photo.convertTo(seen, CV_32F);
        if (flip_x) cv::flip(seen, seen, 1);
        if (flip_y) cv::flip(seen, seen, 0);
        cv::Mat score;
        cv::matchTemplate(seen, patch, score, cv::TM_CCOEFF_NORMED);
        double hi = 0;
        cv::minMaxLoc(score, nullptr, &hi);
        best = std::max(best, hi);
      }
    }
    return best;
  };
  CHECK(inPhoto(t(cv::Rect(0, 0, 64, 64))) > 0.95);
  CHECK(inPhoto(t(cv::Rect(size.width - 64, size.height - 64, 64, 64))) > 0.95);
  // A drawn belt of the same strength is another pattern altogether.
  const cv::Mat belt = ps::detail::surfaceTexture(size, ps::Surface::kBelt, light.texture, 5);
  CHECK(std::abs(correlation(belt, t)) < 0.2);
}

TEST_CASE("a teach frame is a whole frame of the scenes' light, the part where it was asked",
          "[synthetic]") {
  const ps::SilhouetteType type = ps::silhouetteFromPartType("l_shape", 120);
  REQUIRE(!type.mask.empty());
  ps::SilhouetteSceneOptions look;
  look.width = 640;
  look.height = 400;
  look.noise_sigma = 0;
  look.seed = 21;
  REQUIRE(ps::frontLightCondition("low-contrast", &look.front, &look.part_level,
                                  &look.background_level));
  look.parts = 0;
  const cv::Mat empty = ps::SilhouetteScene({type}, {true}, look).render(0);
  const cv::Point2d where(150.3, 290.6);
  cv::Point2d centre;
  const cv::Mat frame = ps::renderSilhouetteInFrame(type, look, look.seed, where, &centre, 30);
  REQUIRE(frame.size() == cv::Size(look.width, look.height));
  // The drawn centroid where it was asked, to the drawing's quarter pixel.
  CHECK(std::abs(centre.x - where.x) <= 0.125 + 1e-9);
  CHECK(std::abs(centre.y - where.y) <= 0.125 + 1e-9);
  // Away from the part, the very levels of a scene of the same seed: the
  // light falls off across the whole frame, not across the part's image.
  cv::Mat away(frame.size(), CV_8UC1, cv::Scalar(255));
  cv::circle(away, cv::Point(150, 290), 100, cv::Scalar(0), cv::FILLED);
  cv::Mat diff;
  cv::absdiff(frame, empty, diff);
  double worst = 0;
  cv::minMaxLoc(diff, nullptr, &worst, nullptr, nullptr, away);
  CHECK(worst == 0);
  // And the part is there: its middle darker than the surface beside it.
  CHECK(cv::mean(frame(cv::Rect(145, 285, 10, 10)))[0] <
        cv::mean(empty(cv::Rect(145, 285, 10, 10)))[0] - 10);
}
