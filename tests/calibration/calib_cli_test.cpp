// picksight-calib end to end on CSV files.
#include <catch2/catch.hpp>

#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "picksight/calibration/robot_camera.hpp"
#include "picksight/tool_support/subprocess.hpp"

using namespace picksight;
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
