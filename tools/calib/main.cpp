// picksight-calib: robot-camera calibration offline, from a CSV of point
// pairs (robot_x,robot_y,vision_x,vision_y, vision in mm). Prints the
// transform, the RMS and every point's residual, and every model's fit
// beside it.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "picksight/calibration/robot_camera.hpp"
#include "picksight/cli/command_line.hpp"
#include "picksight/common/text.hpp"

using namespace picksight;

int main(int argc, char** argv) {
  std::string path;
  std::string method_name = "best";
  cli::App app("Robot-camera calibration from a CSV of point pairs.", "picksight-calib");
  app.setHelpFlag("-h,--help", "print this help");
  app.addOption("--csv", path,
                "a header line, then robot_x,robot_y,vision_x,vision_y per point (mm)")
      ->typeName("FILE")
      ->required();
  const std::vector<calibration::Method> all{
      calibration::Method::kBest,         calibration::Method::kGeometric,
      calibration::Method::kLeastSquares, calibration::Method::kSimilarity,
      calibration::Method::kTilt,         calibration::Method::kHomography};
  std::vector<std::string> names;
  for (auto m : all) names.push_back(calibration::methodName(m));
  app.addOption("--method", method_name, "how to fit the transform")
      ->typeName("best|geometric|lsq|similarity|tilt|homography")
      ->check(cli::isMember(names))
      ->showDefault();
  if (auto exit_code = cli::parseMainArgs(app, argc, argv)) return *exit_code;
  calibration::Method method = calibration::Method::kBest;
  for (auto m : all) {
    if (method_name == calibration::methodName(m)) method = m;
  }
  std::ifstream in(path);
  if (!in) {
    std::cerr << "picksight-calib: cannot read " << path << "\n";
    return 1;
  }
  std::vector<calibration::PointPair> points;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto fields = splitFields(line, ",; \t");
    if (fields.empty() || line[0] == '#') continue;
    if (number == 1 && !parseDouble(fields[0])) continue;  // the header
    if (fields.size() != 4) {
      std::cerr << "picksight-calib: " << path << ":" << number << ": expected 4 numbers, got "
                << fields.size() << "\n";
      return 1;
    }
    double v[4];
    for (int k = 0; k < 4; ++k) {
      auto d = parseDouble(fields[static_cast<size_t>(k)]);
      if (!d) {
        std::cerr << "picksight-calib: " << path << ":" << number << ": '"
                  << std::string(fields[static_cast<size_t>(k)]) << "' is not a number\n";
        return 1;
      }
      v[k] = *d;
    }
    points.push_back({{v[2], v[3]}, {v[0], v[1]}});
  }
  auto result = calibration::calibrate(points, method);
  if (!result) {
    std::cerr << "picksight-calib: " << result.error().message << "\n";
    return 1;
  }
  const auto& t = result->transform;
  std::printf("method %s\nmodel %s\n", calibration::methodName(result->method),
              calibration::modelName(t.model));
  std::printf("dx %s\ndy %s\nrz %s\n", formatFixed(t.dx, 4).c_str(), formatFixed(t.dy, 4).c_str(),
              formatFixed(t.rz_deg, 4).c_str());
  std::printf("scale %s\n", formatFixed(t.scale, 6).c_str());
  std::printf("mirrored %s\n", t.mirrored ? "yes" : "no");
  std::printf("rms %s\ninliers %d of %zu\n", formatFixed(result->rms, 4).c_str(), result->inliers,
              points.size());
  std::printf("%5s %10s %10s %10s %10s %9s %9s %9s %s\n", "point", "robot_x", "robot_y", "vision_x",
              "vision_y", "err_x", "err_y", "err", "");
  for (size_t i = 0; i < points.size(); ++i) {
    const auto& r = result->residuals[i];
    std::printf("%5zu %10.3f %10.3f %10.3f %10.3f %9.4f %9.4f %9.4f %s\n", i + 1, points[i].robot.x,
                points[i].robot.y, points[i].vision.x, points[i].vision.y, r.dx, r.dy, r.distance,
                r.inlier ? "" : "outlier");
  }
  // Every model side by side: the origin, rotation and scale each reads,
  // its RMS (BEST tests the residual sums of squares, docs/PROTOCOL.md) and
  // its cross-validated error.
  std::printf("\n%-10s %-10s %10s %10s %9s %9s %8s %8s %7s\n", "fit", "model", "dx", "dy", "rz",
              "scale", "rms", "cv_rms", "inliers");
  for (auto m : all) {
    if (m == calibration::Method::kBest) continue;
    auto r = calibration::calibrate(points, m);
    if (!r) {
      std::printf("%-10s %-10s %s\n", calibration::methodName(m), "-", r.error().message.c_str());
      continue;
    }
    const auto& f = r->transform;
    std::printf("%-10s %-10s %10.4f %10.4f %9.4f %9.6f %8.4f %8.4f %7d\n",
                calibration::methodName(m), calibration::modelName(f.model), f.dx, f.dy, f.rz_deg,
                f.scale, r->rms, r->predicted_error, r->inliers);
  }
  return 0;
}
