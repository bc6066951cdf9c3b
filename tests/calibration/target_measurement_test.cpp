// Disc and dot-grid targets measured against exact truth: every target is
// rendered by supersampling an analytic ellipse (16 x 16 samples per pixel),
// so its drawn size is known exactly, then blurred, lit unevenly and made
// noisy as a camera would.
#include <catch2/catch.hpp>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <random>

#include "picksight/calibration/target_measurement.hpp"
#include "picksight/common/angles.hpp"

using namespace picksight::calibration;

namespace {
struct Disc {
  cv::Point2d centre;
  double rx = 0;  // semi-axes along image x and y
  double ry = 0;
};

// Coverage of each pixel by the discs (pixel (u, v) covers [u - 0.5, u + 0.5]).
cv::Mat coverage(cv::Size size, const std::vector<Disc>& discs) {
  constexpr int kSuper = 16;
  cv::Mat cov(size, CV_64F, cv::Scalar(0));
  for (const auto& d : discs) {
    const int x0 = std::max(0, static_cast<int>(d.centre.x - d.rx) - 2);
    const int x1 = std::min(size.width - 1, static_cast<int>(d.centre.x + d.rx) + 2);
    const int y0 = std::max(0, static_cast<int>(d.centre.y - d.ry) - 2);
    const int y1 = std::min(size.height - 1, static_cast<int>(d.centre.y + d.ry) + 2);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        int inside = 0;
        for (int sy = 0; sy < kSuper; ++sy) {
          for (int sx = 0; sx < kSuper; ++sx) {
            const double px = x - 0.5 + (sx + 0.5) / kSuper - d.centre.x;
            const double py = y - 0.5 + (sy + 0.5) / kSuper - d.centre.y;
            inside += (px * px) / (d.rx * d.rx) + (py * py) / (d.ry * d.ry) <= 1.0;
          }
        }
        cov.at<double>(y, x) += static_cast<double>(inside) / (kSuper * kSuper);
      }
    }
  }
  return cov;
}

struct Camera {
  double blur_sigma = 1.2;   // optics, pixels
  double noise = 1.0;        // grey levels, standard deviation
  double light_slope = 0.3;  // illumination change across a 1920 x 1080 frame, relative
  bool dark_target = false;
  uint64_t seed = 1;
};

// A camera's view of the coverage: background 60, target 200 (or the other
// way), lit by a ramp, blurred, noisy, 8-bit.
cv::Mat view(const cv::Mat& cov, const Camera& cam) {
  cv::Mat img(cov.size(), CV_64F);
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      const double c = cov.at<double>(y, x);
      const double level = cam.dark_target ? 200 - 140 * c : 60 + 140 * c;
      const double light =
          1.0 - cam.light_slope / 2 + cam.light_slope * (0.7 * x / 1920.0 + 0.3 * y / 1080.0);
      img.at<double>(y, x) = level * light;
    }
  }
  if (cam.blur_sigma > 0) cv::GaussianBlur(img, img, cv::Size(0, 0), cam.blur_sigma);
  std::mt19937_64 rng(cam.seed);
  std::normal_distribution<double> noise(0, cam.noise);
  cv::Mat out(img.size(), CV_8UC1);
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x)
      out.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(img.at<double>(y, x) + noise(rng));
  }
  return out;
}
}  // namespace

TEST_CASE("the drawn mask has the area of the analytic disc", "[calibration][target]") {
  // The truth the other cases rely on: the supersampled mask's area is the
  // disc's to a few parts in 100000 (a rasterizer's is up to 0.15 % off).
  const Disc d{{100.37, 97.81}, 40.0, 40.0};
  const double area = cv::sum(coverage({200, 200}, {d}))[0];
  CHECK(std::abs(area / (M_PI * 40.0 * 40.0) - 1.0) < 5e-5);
}

TEST_CASE("a blurred noisy unevenly lit disc is measured to a hundredth of a pixel",
          "[calibration][target]") {
  // 10 mm radius at 0.25 mm/px: 40 px, the cell; and smaller and
  // larger discs, bright and dark, at sub-pixel centres, blur 0.7 to 2 px.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> frac(0, 1);
  double worst_radius = 0, worst_centre = 0, worst_scale = 0, sum_radius = 0;
  int cases = 0;
  for (double radius : {20.0, 40.0, 61.3}) {
    for (double blur : {0.7, 1.2, 2.0}) {
      for (bool dark : {false, true}) {
        const int side = static_cast<int>(2 * radius + 60);
        const Disc d{{side / 2.0 + frac(rng) - 0.5, side / 2.0 + frac(rng) - 0.5}, radius, radius};
        Camera cam;
        cam.blur_sigma = blur;
        cam.dark_target = dark;
        cam.seed = static_cast<uint64_t>(++cases);
        const cv::Mat img = view(coverage({side, side}, {d}), cam);
        // A guess as rough as a thresholded region gives.
        auto m = measureDisc(img, d.centre + cv::Point2d(0.7, -0.5), radius * 1.04);
        REQUIRE(m);
        INFO("radius " << radius << " blur " << blur << (dark ? " dark" : " bright") << ": rx "
                       << m->radius_x << " ry " << m->radius_y << " centre " << m->centre);
        const double r_err =
            std::max(std::abs(m->radius_x - radius), std::abs(m->radius_y - radius));
        const double c_err = cv::norm(m->centre - d.centre);
        // The noise alone moves a 40 px disc's radius by about 0.01 px
        // (standard deviation) at 1 grey level of noise on a step of 140;
        // the target (40 px and more) has its scale within 0.04 %.
        CHECK(r_err < 0.025);
        CHECK(c_err < 0.02);
        sum_radius += (m->radius_x + m->radius_y) / 2 - radius;
        auto scale = scaleFromDisc(*m, radius * 0.25);
        REQUIRE(scale);
        const double s_err = std::max(std::abs(scale->mm_per_px_x / 0.25 - 1),
                                      std::abs(scale->mm_per_px_y / 0.25 - 1));
        if (radius >= 40) CHECK(s_err < 0.0004);
        CHECK(m->edge_width == Approx(blur).margin(0.1));
        worst_radius = std::max(worst_radius, r_err);
        worst_centre = std::max(worst_centre, c_err);
        worst_scale = std::max(worst_scale, s_err);
      }
    }
  }
  // No bias: the mean radius error over all cases is a fraction of the noise.
  CHECK(std::abs(sum_radius / cases) < 0.005);
  WARN("disc, worst of " << cases << " cases: radius " << worst_radius << " px, centre "
                         << worst_centre << " px, scale " << worst_scale * 100
                         << " %; mean radius error " << sum_radius / cases << " px");
}

TEST_CASE("non-square pixels give each axis its own scale", "[calibration][target]") {
  // 20 mm radius at 0.25 mm/px across and 0.2 mm/px down.
  const Disc d{{150.3, 160.6}, 80.0, 100.0};
  const cv::Mat img = view(coverage({300, 320}, {d}), Camera{});
  auto m = measureDisc(img, {150, 160}, 90);
  REQUIRE(m);
  CHECK(m->radius_x == Approx(80).margin(0.03));
  CHECK(m->radius_y == Approx(100).margin(0.03));
  auto s = scaleFromDisc(*m, 20.0);
  REQUIRE(s);
  CHECK(s->mm_per_px_x == Approx(0.25).epsilon(0.0003));
  CHECK(s->mm_per_px_y == Approx(0.20).epsilon(0.0003));
  CHECK(s->skew_deg < 0.5);
}

TEST_CASE("what is not a measurable disc is refused", "[calibration][target]") {
  const cv::Mat flat(100, 100, CV_8UC1, cv::Scalar(90));
  auto m = measureDisc(flat, {50, 50}, 20);
  REQUIRE_FALSE(m);
  CHECK(m.error().code == CalibrationErrc::kBadTarget);
  CHECK_FALSE(measureDisc(flat, {50, 50}, 0.5));
  CHECK_FALSE(measureDisc(flat, {500, 50}, 20));
  CHECK_FALSE(measureDisc(cv::Mat(), {50, 50}, 20));
  CHECK_FALSE(scaleFromDisc(DiscMeasurement{}, 10));
}

TEST_CASE("a dot grid gives the scale on X and on Y", "[calibration][target]") {
  // 7 x 5 dots, 10 mm apart, 2.5 mm radius, seen at 0.25 mm/px across and
  // 0.2495 mm/px down (0.2 % apart), the grid turned 7 degrees.
  const double sx = 0.25, sy = 0.2495, pitch = 10, rot = 7 * M_PI / 180;
  std::vector<Disc> dots;
  for (int j = 0; j < 5; ++j) {
    for (int i = 0; i < 7; ++i) {
      const double mx = (i - 3) * pitch, my = (j - 2) * pitch;
      const double x = std::cos(rot) * mx - std::sin(rot) * my;
      const double y = std::sin(rot) * mx + std::cos(rot) * my;
      dots.push_back({{200.3 + x / sx, 150.8 + y / sy}, 2.5 / sx, 2.5 / sy});
    }
  }
  Camera cam;
  cam.dark_target = true;
  const cv::Mat img = view(coverage({400, 300}, dots), cam);
  auto g = measureDotGrid(img, pitch);
  REQUIRE(g);
  CHECK(g->dots == 35);
  CHECK(g->cols == 7);
  CHECK(g->rows == 5);
  CHECK(picksight::angleDiffDeg(g->rotation_deg, 7, 180) < 0.02);
  CHECK(g->scale.mm_per_px_x == Approx(sx).epsilon(0.0002));
  CHECK(g->scale.mm_per_px_y == Approx(sy).epsilon(0.0002));
  CHECK(g->grid_rms_px < 0.05);
  CHECK(g->scale.skew_deg < 0.05);
  WARN("dot grid: " << g->scale.mm_per_px_x << " x " << g->scale.mm_per_px_y
                    << " mm/px (truth 0.25 x 0.2495), grid RMS " << g->grid_rms_px << " px");
  // A single disc is no grid.
  const cv::Mat one = view(coverage({200, 200}, {Disc{{100, 100}, 30, 30}}), cam);
  CHECK_FALSE(measureDotGrid(one, pitch));
  CHECK_FALSE(measureDotGrid(img, 0));
}
