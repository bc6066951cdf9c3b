// The similarity and homography fits and BEST's choice between models, on
// synthetic cells: a camera scale a fraction of a percent off, a tilted
// camera, rotations all round (180 degrees included), mirrored frames, few
// points, points nearly on a line, outliers.
#include <catch2/catch.hpp>

#include "calibration_cell.hpp"

#include <cmath>

#include "picksight/calibration/robot_camera.hpp"
#include "picksight/common/angles.hpp"

using namespace picksight::calibration;
using picksight::test::CalibrationCell;
using picksight::test::CellSpec;
using picksight::test::makeCalibrationCell;

namespace {
// Pooled RMS misplacement over `cells` random cells built by `spec_for`.
template <typename SpecFor>
double pooledRms(Method method, int cells, SpecFor spec_for, int* chose_model = nullptr,
                 TransformModel model = TransformModel::kRigid) {
  double sum = 0;
  for (int c = 0; c < cells; ++c) {
    const CalibrationCell cell = makeCalibrationCell(spec_for(c));
    auto r = calibrate(cell.points, method);
    REQUIRE(r);
    const double e = cell.placementRms(r->transform);
    sum += e * e;
    if (chose_model) *chose_model += r->transform.model == model;
  }
  return std::sqrt(sum / cells);
}

CellSpec randomCell(int c) {
  CellSpec s;
  s.seed = static_cast<uint64_t>(c + 1);
  s.robot.rz_deg = picksight::signedDeg(-178.7 + 37.3 * c);
  s.robot.dx = 300 + 5 * c;
  s.robot.dy = -600 + 3 * c;
  return s;
}

// A random cell seen by a camera tilted by 2 degrees, its scale 0.3 % off.
CellSpec tiltedCell(int c, int points) {
  CellSpec s = randomCell(c);
  s.points = points;
  s.scale_error = 0.003;
  s.tilt_deg = 2;
  s.tilt_axis_deg = 17.0 * c;
  return s;
}
}  // namespace

TEST_CASE("noise-free points give each model back exactly", "[calibration][models]") {
  CellSpec s;
  s.points = 8;
  s.robot_noise = 0;
  s.scale_error = 0.003;
  auto cell = makeCalibrationCell(s);
  auto r = calibrate(cell.points, Method::kSimilarity);
  REQUIRE(r);
  CHECK(r->transform.model == TransformModel::kSimilarity);
  CHECK(r->transform.scale == Approx(1 / 1.003).epsilon(1e-9));
  CHECK(r->transform.rz_deg == Approx(37.25).margin(1e-9));
  CHECK(cell.placementRms(r->transform) < 1e-9);
  s.tilt_deg = 2;
  cell = makeCalibrationCell(s);
  r = calibrate(cell.points, Method::kHomography);
  REQUIRE(r);
  CHECK(r->transform.model == TransformModel::kHomography);
  CHECK(cell.placementRms(r->transform) < 1e-6);
  CHECK(r->inliers == 8);
  // BEST takes the homography for a tilted camera.
  r = calibrate(cell.points, Method::kBest);
  REQUIRE(r);
  CHECK(r->method == Method::kHomography);
}

TEST_CASE("a camera scale 0.3 % off: the similarity fit places parts within 0.05 mm",
          "[calibration][models]") {
  // The goal: 0.05 mm of noise on the robot points, a camera scale
  // wrong by 0.3 %, 6 or more points over 360 x 170 mm: robot-frame error at
  // most 0.05 mm RMS over the work area, pooled over 40 cells at rotations
  // all round. The rigid fit cannot: 0.3 % of 180 mm is 0.54 mm.
  for (int points : {6, 7, 12}) {
    const auto spec = [&](int c) {
      CellSpec s = randomCell(c);
      s.points = points;
      s.scale_error = 0.003;
      return s;
    };
    int similar = 0;
    const double best = pooledRms(Method::kBest, 40, spec, &similar, TransformModel::kSimilarity);
    const double sim = pooledRms(Method::kSimilarity, 40, spec);
    const double lsq = pooledRms(Method::kLeastSquares, 40, spec);
    INFO(points << " points: BEST " << best << " mm (similarity chosen " << similar
                << " of 40), SIMILARITY " << sim << " mm, LSQ " << lsq << " mm");
    CHECK(best <= 0.05);
    CHECK(sim <= 0.05);
    CHECK(lsq > 0.2);
    CHECK(similar >= 36);
  }
}

TEST_CASE("a camera tilted by 2 degrees: the homography places parts within 0.1 mm",
          "[calibration][models]") {
  for (int points : {8, 12}) {
    const auto spec = [&](int c) {
      CellSpec s = randomCell(c);
      s.points = points;
      s.scale_error = 0.003;
      s.tilt_deg = 2;
      s.tilt_axis_deg = 17.0 * c;
      return s;
    };
    int homographies = 0;
    const double best =
        pooledRms(Method::kBest, 40, spec, &homographies, TransformModel::kHomography);
    const double homography = pooledRms(Method::kHomography, 40, spec);
    const double sim = pooledRms(Method::kSimilarity, 40, spec);
    INFO(points << " points: BEST " << best << " mm (homography chosen " << homographies
                << " of 40), HOMOGRAPHY " << homography << " mm, SIMILARITY " << sim << " mm");
    // The goal. (With cross-validated errors and a 20 % margin BEST pooled
    // 0.14 mm over these 40 cells at 8 points.)
    CHECK(best <= 0.1);
    CHECK(homography <= 0.1);
    CHECK(sim > 0.15);
  }
}

TEST_CASE("a camera tilted by 2 degrees seen from 7 points: BEST takes the tilt model",
          "[calibration][models]") {
  // Too few points to judge a homography's 8 parameters against the noise;
  // the tilt model's 6 (the similarity and the perspective's two) fit.
  const auto spec = [](int c) { return tiltedCell(c, 7); };
  int tilts = 0;
  const double best = pooledRms(Method::kBest, 40, spec, &tilts, TransformModel::kTilt);
  const double tilt = pooledRms(Method::kTilt, 40, spec);
  const double sim = pooledRms(Method::kSimilarity, 40, spec);
  INFO("BEST " << best << " mm (tilt chosen " << tilts << " of 40), TILT " << tilt
               << " mm, SIMILARITY " << sim << " mm");
  CHECK(tilts >= 34);
  CHECK(tilt <= 0.12);
  CHECK(best <= 0.15);
  CHECK(sim > 3 * tilt);
  // Without noise the tilt model is off by the tilt's second order only (a
  // 2 x 2 block 6e-4 from a similarity at 2 degrees: 0.07 mm RMS on this
  // cell, the price of its two fewer parameters).
  CellSpec exact = spec(3);
  exact.robot_noise = 0;
  const auto cell = makeCalibrationCell(exact);
  auto r = calibrate(cell.points, Method::kTilt);
  REQUIRE(r);
  CHECK(r->transform.model == TransformModel::kTilt);
  INFO("noise-free tilt fit: " << cell.placementRms(r->transform) << " mm");
  CHECK(cell.placementRms(r->transform) < 0.1);
}

TEST_CASE("a camera tilted by 2 degrees seen from 6 points: BEST offers the tilt model",
          "[calibration][models]") {
  // 6 inliers are the fewest BEST tries the tilt with (kTiltBestInliers):
  // 33 of these 40 cells take it; asked for 7, none would.
  const auto spec = [](int c) { return tiltedCell(c, 6); };
  int tilts = 0;
  const double best = pooledRms(Method::kBest, 40, spec, &tilts, TransformModel::kTilt);
  const double sim = pooledRms(Method::kSimilarity, 40, spec);
  INFO("BEST " << best << " mm (tilt chosen " << tilts << " of 40), SIMILARITY " << sim << " mm");
  CHECK(tilts >= 28);
  CHECK(best < sim);
}

TEST_CASE("genuine points of a tilted camera stay inliers of the tilt fit",
          "[calibration][models]") {
  // The tilt's 3-point hypothesis extrapolates poorly; its core (3 cuts)
  // lets the refit, not the hypothesis, judge points far from the sample.
  // 7 points spread over the work area, 100 cells: none cut; 8 with the
  // core at one cut.
  int cut = 0;
  for (int c = 0; c < 100; ++c) {
    auto r = calibrate(makeCalibrationCell(tiltedCell(c, 7)).points, Method::kTilt);
    REQUIRE(r);
    for (const auto& residual : r->residuals) cut += !residual.inlier;
  }
  INFO(cut << " genuine points of 700 cut");
  CHECK(cut <= 2);
}

TEST_CASE("with a true camera BEST keeps the simpler model", "[calibration][models]") {
  // No scale error, no tilt: the extra parameters only fit the noise, and
  // the prediction-error penalty must say so most of the time.
  int rigid = 0;
  const auto spec = [](int c) {
    CellSpec s = randomCell(c);
    s.points = 10;
    return s;
  };
  for (int c = 0; c < 40; ++c) {
    auto r = calibrate(makeCalibrationCell(spec(c)).points, Method::kBest);
    REQUIRE(r);
    rigid += r->transform.model == TransformModel::kRigid;
    CHECK(r->transform.model != TransformModel::kHomography);
  }
  CHECK(rigid >= 24);
  CHECK(pooledRms(Method::kBest, 40, spec) < 0.05);
}

TEST_CASE("rotations near 180 degrees and mirrored frames", "[calibration][models]") {
  for (double rz : {180.0, -179.99, 179.5, 0.0, 90.0, -90.0}) {
    for (bool mirrored : {false, true}) {
      CellSpec s;
      s.robot = {328.4, -614.4, rz, mirrored};
      s.points = 9;
      s.scale_error = -0.002;
      auto cell = makeCalibrationCell(s);
      for (Method m : {Method::kBest, Method::kLeastSquares, Method::kGeometric,
                       Method::kSimilarity, Method::kTilt, Method::kHomography}) {
        INFO("rz " << rz << (mirrored ? " mirrored " : " ") << methodName(m));
        auto r = calibrate(cell.points, m);
        REQUIRE(r);
        CHECK(r->transform.mirrored == mirrored);
        CHECK(picksight::angleDiffDeg(r->transform.rz_deg, rz) < 0.1);
        CHECK(r->transform.rz_deg > -180.0);
        CHECK(r->transform.rz_deg <= 180.0);
        const double bound = m == Method::kLeastSquares || m == Method::kGeometric ? 0.6 : 0.1;
        CHECK(cell.placementRms(r->transform) < bound);
        CHECK(r->inliers == 9);
        // An angle turns with the frame, the other way when mirrored.
        const double expected = picksight::normalizeDeg(mirrored ? rz - 10 : rz + 10);
        CHECK(picksight::angleDiffDeg(r->transform.applyToAngleDeg(10, {50, 20}), expected) < 0.2);
      }
    }
  }
}

TEST_CASE("outliers are found by every model", "[calibration][models]") {
  for (int c = 0; c < 20; ++c) {
    CellSpec s = randomCell(c);
    s.points = 14;
    s.outliers = 3;
    s.scale_error = 0.003;
    s.tilt_deg = c % 2 ? 2 : 0;
    const auto cell = makeCalibrationCell(s);
    for (Method m : {Method::kBest, Method::kSimilarity, Method::kHomography}) {
      if (s.tilt_deg > 0 && m == Method::kSimilarity) continue;
      INFO("cell " << c << " " << methodName(m));
      auto r = calibrate(cell.points, m);
      REQUIRE(r);
      for (size_t i = 0; i < cell.points.size(); ++i) {
        if (cell.outlier[i]) CHECK_FALSE(r->residuals[i].inlier);
      }
      CHECK(r->inliers >= 10);
      // 11 genuine points; a tilted camera's 8-parameter fit is the weaker.
      CHECK(cell.placementRms(r->transform) < (s.tilt_deg > 0 ? 0.15 : 0.1));
    }
  }
}

TEST_CASE("few points and points nearly on a line", "[calibration][models]") {
  CellSpec s;
  s.points = 5;
  auto cell = makeCalibrationCell(s);
  auto r = calibrate(cell.points, Method::kHomography);
  REQUIRE_FALSE(r);
  CHECK(r.error().code == CalibrationErrc::kTooFewPoints);
  CHECK(r.error().message.find("6") != std::string::npos);
  // With 5 points BEST never offers the homography.
  r = calibrate(cell.points, Method::kBest);
  REQUIRE(r);
  CHECK(r->transform.model != TransformModel::kHomography);
  // Three points: every model but the homography.
  cell.points.resize(3);
  for (Method m : {Method::kBest, Method::kLeastSquares, Method::kGeometric, Method::kSimilarity}) {
    INFO(methodName(m));
    r = calibrate(cell.points, m);
    INFO((r ? std::string() : r.error().message));
    REQUIRE(r);
    CHECK(r->inliers == 3);
  }
  // Points 2 mm off one line over 300 mm: still a plane, though a weak one;
  // 0.5 mm off: refused.
  for (double off : {2.0, 0.5}) {
    std::vector<PointPair> line;
    for (int i = 0; i < 8; ++i) {
      const cv::Point2d v(-150 + 40.0 * i, (i % 2 ? off : -off));
      line.push_back({v, s.robot.apply(v)});
    }
    for (Method m : {Method::kBest, Method::kSimilarity, Method::kHomography}) {
      INFO(off << " mm " << methodName(m));
      r = calibrate(line, m);
      if (off < 1) {
        REQUIRE_FALSE(r);
        CHECK(r.error().code == CalibrationErrc::kDegeneratePoints);
      } else {
        REQUIRE(r);
        CHECK(cv::norm(r->transform.apply({0, 0}) - s.robot.apply({0, 0})) < 0.01);
      }
    }
  }
}

TEST_CASE("non-finite coordinates are refused with the point named", "[calibration][models]") {
  auto cell = makeCalibrationCell(CellSpec{});
  cell.points[4].robot.x = std::nan("");
  auto r = calibrate(cell.points);
  REQUIRE_FALSE(r);
  CHECK(r.error().code == CalibrationErrc::kBadInput);
  CHECK(r.error().message.find("point 5") != std::string::npos);
  CHECK_FALSE(PlaneTransform::homography(cv::Matx33d::zeros()));
  cv::Matx33d inf = cv::Matx33d::eye();
  inf(0, 1) = INFINITY;
  CHECK_FALSE(PlaneTransform::homography(inf));
}

TEST_CASE("the same points always give the same result", "[calibration][models]") {
  // Random samples are drawn with a fixed seed: a robot program that
  // recomputes gets the transform it had.
  CellSpec s = randomCell(3);
  s.points = 60;
  s.outliers = 10;
  s.tilt_deg = 1;
  const auto cell = makeCalibrationCell(s);
  auto a = calibrate(cell.points, Method::kBest);
  auto b = calibrate(cell.points, Method::kBest);
  REQUIRE(a);
  REQUIRE(b);
  CHECK(a->transform.matrix == b->transform.matrix);
  CHECK(a->inliers == b->inliers);
}
