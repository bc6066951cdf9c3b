// Camera scale from a circular target, and the lens model from OpenCV's
// public chessboard views against OpenCV's own calibration of them.
#include <catch2/catch.hpp>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include "picksight/codecs/codecs.hpp"

#include "picksight/calibration/camera_calibration.hpp"

using namespace picksight::calibration;

namespace {
const std::string kBoardDir =
    std::string(PICKSIGHT_TEST_DATA_DIR) + "/calibration/opencv_chessboard/";

// Moments of an ellipse of semi-axes a, b (pixels), drawn 8x larger and
// averaged down so edges are partial pixels as a camera sees them.
cv::Moments ellipseMoments(double a, double b) {
  constexpr int kSuper = 8;
  cv::Mat big(400 * kSuper, 400 * kSuper, CV_8UC1, cv::Scalar(0));
  cv::ellipse(
      big,
      cv::RotatedRect(
          {200.f * kSuper, 200.f * kSuper},
          cv::Size2f(static_cast<float>(2 * a * kSuper), static_cast<float>(2 * b * kSuper)), 0),
      cv::Scalar(255), cv::FILLED, cv::LINE_8);
  cv::Mat small;
  cv::resize(big, small, cv::Size(400, 400), 0, 0, cv::INTER_AREA);
  return cv::moments(small, false);
}
}  // namespace

TEST_CASE("a circle's image gives millimetres per pixel on each axis", "[calibration][camera]") {
  // A 20 mm radius disc seen at 0.25 mm/px in x and 0.2 mm/px in y.
  auto s = scaleFromCircle(ellipseMoments(80, 100), 20.0);
  REQUIRE(s);
  CHECK(s->mm_per_px_x == Approx(0.25).epsilon(0.002));
  CHECK(s->mm_per_px_y == Approx(0.20).epsilon(0.002));
  CHECK(s->skew_deg < 0.5);
  CHECK_FALSE(scaleFromCircle(ellipseMoments(80, 100), 0));
  CHECK_FALSE(scaleFromCircle(cv::Moments(), 10));
}

TEST_CASE("the chessboard views give OpenCV's own calibration of them", "[calibration][camera]") {
  std::vector<cv::Mat> views;
  for (int i : {1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14}) {
    char name[32];
    std::snprintf(name, sizeof(name), "left%02d.jpg", i);
    views.push_back(picksight::codecs::imread(kBoardDir + name, cv::IMREAD_GRAYSCALE));
    REQUIRE_FALSE(views.back().empty());
  }
  cv::FileStorage stored(kBoardDir + "left_intrinsics.yml", cv::FileStorage::READ);
  REQUIRE(stored.isOpened());
  cv::Mat k_ref;
  stored["camera_matrix"] >> k_ref;
  const double err_ref = static_cast<double>(stored["avg_reprojection_error"]);

  std::vector<int> skipped;
  auto model = calibrateChessboard(views, {}, &skipped);
  REQUIRE(model);
  CHECK(model->views + static_cast<int>(skipped.size()) == 13);
  CHECK(model->views >= 12);
  CHECK(model->camera_matrix(0, 0) == Approx(k_ref.at<double>(0, 0)).epsilon(0.01));
  CHECK(model->camera_matrix(1, 1) == Approx(k_ref.at<double>(1, 1)).epsilon(0.01));
  CHECK(model->camera_matrix(0, 2) == Approx(k_ref.at<double>(0, 2)).margin(3.0));
  CHECK(model->camera_matrix(1, 2) == Approx(k_ref.at<double>(1, 2)).margin(3.0));
  CHECK(model->rms_reprojection_px < 2 * err_ref);
  WARN("lens model: fx " << model->camera_matrix(0, 0) << " fy " << model->camera_matrix(1, 1)
                         << " cx " << model->camera_matrix(0, 2) << " cy "
                         << model->camera_matrix(1, 2) << ", RMS " << model->rms_reprojection_px
                         << " px over " << model->views << " views (OpenCV's: fx "
                         << k_ref.at<double>(0, 0) << ", RMS " << err_ref << ")");

  // Undistorting the corners of a view makes the board's rows straight.
  std::vector<cv::Point2f> corners;
  REQUIRE(cv::findChessboardCorners(views[0], cv::Size(9, 6), corners));
  std::vector<cv::Point2d> row_raw, row;
  for (int x = 0; x < 9; ++x) row_raw.emplace_back(corners[static_cast<size_t>(x)]);
  row = model->undistort(row_raw);
  auto straightness = [](const std::vector<cv::Point2d>& pts) {
    cv::Vec4f line;
    std::vector<cv::Point2f> f(pts.begin(), pts.end());
    cv::fitLine(f, line, cv::DIST_L2, 0, 0.01, 0.01);
    double worst = 0;
    for (const auto& p : pts) {
      worst = std::max(worst, std::abs((p.x - line[2]) * line[1] - (p.y - line[3]) * line[0]));
    }
    return worst;
  };
  CHECK(straightness(row) < straightness(row_raw));
  CHECK(straightness(row) < 0.5);

  // The stored form reads back the same model; damaged text is refused.
  auto back = lensModelFromYaml(lensModelToYaml(*model));
  REQUIRE(back);
  CHECK(back->camera_matrix(0, 0) == Approx(model->camera_matrix(0, 0)));
  CHECK(back->distortion == model->distortion);
  CHECK_FALSE(lensModelFromYaml("%YAML:1.0\n---\nformat_version: 1\n"));
  CHECK_FALSE(lensModelFromYaml("not yaml at all: ["));
}
