// picksight-calib end to end on CSV files.
#include <catch2/catch.hpp>

#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <string>

#include "calibration_cell.hpp"
#include "picksight/calibration/robot_camera.hpp"
#include "picksight/common/angles.hpp"
#include "picksight/tool_support/subprocess.hpp"

using namespace picksight;
using namespace picksight::tool_support;
using namespace std::chrono_literals;

namespace {
struct Run {
  int code = -1;
  std::string out;
};

Run calib(const std::vector<std::string>& args) {
  std::vector<std::string> argv = {std::string(PICKSIGHT_BIN_DIR) + "/picksight-calib"};
  argv.insert(argv.end(), args.begin(), args.end());
  Subprocess p(argv);
  Run r;
  while (auto line = p.readLine(10s)) r.out += *line + "\n";
  auto status = p.wait(10s);
  REQUIRE(status);
  r.code = WIFEXITED(*status) ? WEXITSTATUS(*status) : -1;
  return r;
}

struct FitRow {
  std::string model;
  double dx = 0, dy = 0, rz = 0, scale = 0, rms = 0, cv_rms = 0;
  int inliers = 0;
};

// The row of `fit` in picksight-calib's side-by-side table, or nullopt.
std::optional<FitRow> fitRow(const std::string& out, const std::string& fit) {
  const size_t table = out.find("\nfit ");
  if (table == std::string::npos) return std::nullopt;
  const size_t at = out.find("\n" + fit + " ", table + 1);
  if (at == std::string::npos) return std::nullopt;
  FitRow r;
  char model[32] = "";
  if (std::sscanf(out.c_str() + at + 1 + fit.size(), " %31s %lf %lf %lf %lf %lf %lf %d", model,
                  &r.dx, &r.dy, &r.rz, &r.scale, &r.rms, &r.cv_rms, &r.inliers) != 8)
    return std::nullopt;
  r.model = model;
  return r;
}

// A CSV of the cell's points (vision in mm), as a robot program would log them.
std::string cellCsv(const test::CalibrationCell& cell) {
  std::string csv = "robot_x,robot_y,vision_x,vision_y\n";
  for (const auto& p : cell.points) {
    char row[160];
    std::snprintf(row, sizeof(row), "%.6f,%.6f,%.6f,%.6f\n", p.robot.x, p.robot.y, p.vision.x,
                  p.vision.y);
    csv += row;
  }
  return csv;
}

std::string tempCsv(const std::string& content) {
  char name[] = "/tmp/picksight-calib-XXXXXX";
  const int fd = mkstemp(name);
  REQUIRE(fd >= 0);
  close(fd);
  std::ofstream(name) << content;
  return name;
}
}  // namespace

TEST_CASE("picksight-calib prints the transform and every residual", "[calibration][cli]") {
  const calibration::RigidTransform truth{100, 50, 90, false};
  std::string csv = "robot_x,robot_y,vision_x,vision_y\n";
  for (auto v :
       {cv::Point2d(0, 0), cv::Point2d(100, 0), cv::Point2d(0, 80), cv::Point2d(120, 90)}) {
    const cv::Point2d r = truth.apply(v);
    char row[128];
    std::snprintf(row, sizeof(row), "%.4f,%.4f,%.4f,%.4f\n", r.x, r.y, v.x, v.y);
    csv += row;
  }
  const std::string path = tempCsv(csv);
  for (const std::string method : {"lsq", "geometric", "best"}) {
    const Run r = calib({"--csv", path, "--method", method});
    INFO(r.out);
    CHECK(r.code == 0);
    CHECK(r.out.find("dx 100.0000") != std::string::npos);
    CHECK(r.out.find("dy 50.0000") != std::string::npos);
    CHECK(r.out.find("rz 90.0000") != std::string::npos);
    CHECK(r.out.find("inliers 4 of 4") != std::string::npos);
  }
  std::remove(path.c_str());
}

TEST_CASE("picksight-calib names the bad line and refuses too few points", "[calibration][cli]") {
  const std::string bad = tempCsv("robot_x,robot_y,vision_x,vision_y\n1,2,3,4\n1,2,x,4\n");
  Run r = calib({"--csv", bad});
  CHECK(r.code == 1);
  const std::string few = tempCsv("robot_x,robot_y,vision_x,vision_y\n1,2,3,4\n5,6,7,9\n");
  r = calib({"--csv", few});
  CHECK(r.code == 1);
  CHECK(calib({"--csv", "/nonexistent/points.csv"}).code == 1);
  CHECK(calib({"--method", "magic"}).code == 2);
  std::remove(bad.c_str());
  std::remove(few.c_str());
}

TEST_CASE("picksight-calib prints every model's fit beside the chosen one", "[calibration][cli]") {
  // A camera scale 0.3 % off: the similarity and homography read it.
  std::string csv = "robot_x,robot_y,vision_x,vision_y\n";
  const calibration::RigidTransform turn{328.4, -614.4, -179.0, false};
  for (int i = 0; i < 9; ++i) {
    const cv::Point2d v(-150.0 + 150.0 * (i % 3), -70.0 + 70.0 * (i / 3) + (i % 2) * 3.0);
    const cv::Point2d r = turn.apply(v / 1.003);
    char row[128];
    std::snprintf(row, sizeof(row), "%.5f,%.5f,%.5f,%.5f\n", r.x, r.y, v.x, v.y);
    csv += row;
  }
  const std::string path = tempCsv(csv);
  const Run r = calib({"--csv", path});
  INFO(r.out);
  CHECK(r.code == 0);
  CHECK(r.out.find("method similarity") != std::string::npos);
  CHECK(r.out.find("scale 0.997009") != std::string::npos);
  CHECK(r.out.find("dx 328.4000") != std::string::npos);
  CHECK(r.out.find("rz 181.0000") == std::string::npos);  // (-180, 180]: -179
  CHECK(r.out.find("rz -179.0000") != std::string::npos);
  for (const char* fit : {"\nlsq ", "\ngeometric ", "\nsimilarity ", "\nhomography "})
    CHECK(r.out.find(fit) != std::string::npos);
  std::remove(path.c_str());
}

TEST_CASE("picksight-calib reads a known tilted camera from a CSV with every fit side by side",
          "[calibration][cli]") {
  // A camera tilted 2 degrees with its scale 0.3 % off, the robot frame at
  // the paper's origin and rotation, 12 exact points: the homography reads
  // the truth; the rigid fits (least squares and the paper's geometric
  // method) and the similarity cannot, and say so by their residuals.
  test::CellSpec spec;
  spec.robot = {328.4, -614.4, -179.0, false};
  spec.points = 12;
  spec.robot_noise = 0;
  spec.scale_error = 0.003;
  spec.tilt_deg = 2;
  const auto cell = test::makeCalibrationCell(spec);
  const auto truth = *calibration::PlaneTransform::homography(cell.vision_to_robot);
  const std::string path = tempCsv(cellCsv(cell));
  const Run r = calib({"--csv", path});
  INFO(r.out);
  CHECK(r.code == 0);
  CHECK(r.out.find("method homography") != std::string::npos);
  const auto lsq = fitRow(r.out, "lsq"), geometric = fitRow(r.out, "geometric"),
             similarity = fitRow(r.out, "similarity"), tilt = fitRow(r.out, "tilt"),
             homography = fitRow(r.out, "homography");
  REQUIRE(lsq);
  REQUIRE(geometric);
  REQUIRE(similarity);
  REQUIRE(tilt);
  REQUIRE(homography);
  CHECK(lsq->model == "rigid");
  CHECK(geometric->model == "rigid");
  CHECK(similarity->model == "similarity");
  CHECK(tilt->model == "tilt");
  CHECK(homography->model == "homography");
  // The homography: the truth's origin, rotation and local scale, no residual.
  CHECK(homography->dx == Approx(truth.dx).margin(2e-3));
  CHECK(homography->dy == Approx(truth.dy).margin(2e-3));
  CHECK(picksight::angleDiffDeg(homography->rz, truth.rz_deg) < 2e-3);
  CHECK(homography->scale == Approx(truth.scale).margin(2e-5));
  CHECK(homography->rms < 1e-3);
  CHECK(homography->inliers == 12);
  // The rigid fits keep the scale at 1 and miss by tenths of a millimetre.
  CHECK(lsq->scale == 1.0);
  CHECK(geometric->scale == 1.0);
  CHECK(lsq->rms > 0.1);
  CHECK(geometric->rms > 0.1);
  // The similarity reads a scale but not the tilt; the tilt model nearly all.
  CHECK(similarity->rms > 0.1);
  CHECK(tilt->rms < similarity->rms / 3);
  // Every fit reads the rotation to a tenth of a degree.
  for (const auto& row : {*lsq, *geometric, *similarity, *tilt, *homography})
    CHECK(picksight::angleDiffDeg(row.rz, -179.0) < 0.1);
  std::remove(path.c_str());
}

TEST_CASE("picksight-calib on the paper's Table 2 reads its origin and rotation",
          "[calibration][cli]") {
  // The 17 point pairs the paper publishes (tests/data/calibration/
  // paper_table2/README.md): a least-squares rigid fit places the vision
  // frame at (328.4, -614.4) mm turned 181.0 degrees; the similarity and the
  // homography are printed beside it, so a reader sees what a scale or a
  // tilt would change.
  const std::string path =
      std::string(PICKSIGHT_TEST_DATA_DIR) + "/calibration/paper_table2/points.csv";
  const Run r = calib({"--csv", path});
  INFO(r.out);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("inliers 17 of 17") != std::string::npos);
  const auto lsq = fitRow(r.out, "lsq");
  REQUIRE(lsq);
  CHECK(lsq->model == "rigid");
  CHECK(lsq->dx == Approx(328.4).margin(0.1));
  CHECK(lsq->dy == Approx(-614.4).margin(0.1));
  CHECK(picksight::angleDiffDeg(lsq->rz, 181.0) < 0.05);
  CHECK(lsq->inliers == 17);
  const auto similarity = fitRow(r.out, "similarity"), homography = fitRow(r.out, "homography");
  REQUIRE(similarity);
  REQUIRE(homography);
  CHECK(similarity->model == "similarity");
  CHECK(homography->model == "homography");
  // Whole-millimetre vision coordinates: every fit is about a millimetre off.
  for (const auto& row : {*lsq, *similarity, *homography}) {
    CHECK(row.rms > 0.5);
    CHECK(row.rms < 2.0);
  }
}
