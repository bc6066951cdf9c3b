// The cell's calibration under load and damage: COMPUTE fits without the
// lock LOCATE and STATUS take, the stored points have a cap, non-finite
// numbers are refused, and a damaged file blocks LOCATE's geometry until
// it is cleared.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <future>
#include <limits>
#include <regex>
#include <thread>

#include "picksight/common/atomic_file.hpp"
#include "picksight/store/cell_calibration.hpp"
#include "temp_dir.hpp"

using namespace picksight;
using namespace picksight::store;

namespace {

// Points of a robot frame turned by 90 degrees and moved by (100, 50).
calibration::PointPair pointAt(double x, double y) { return {{x, y}, {100 - y, 50 + x}}; }

void storeSquare(CellCalibration& c) {
  for (const auto& p : {pointAt(0, 0), pointAt(40, 0), pointAt(40, 30), pointAt(0, 30)}) {
    REQUIRE(c.addPoint(p));
  }
}

// A fit that reports when it starts and finishes only when released: holds a
// COMPUTE in progress for as long as the test needs, with no timing.
struct HeldFit {
  std::promise<void> started;
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();

  CellCalibration::Fit fit() {
    return [this](const std::vector<calibration::PointPair>& points, calibration::Method method) {
      started.set_value();
      released.wait();
      return calibration::calibrate(points, method);
    };
  }
};

// A calibration of four points in `dir` whose COMPUTE, started on another
// thread, is held in its fit until `held` releases it.
struct HeldCompute {
  HeldFit held;
  CellCalibration calibration;
  std::future<Result<calibration::CalibrationResult>> result;

  explicit HeldCompute(const test::TempDir& dir)
      : calibration(dir.file("calibration.yaml"), held.fit()) {
    REQUIRE(calibration.load());
    storeSquare(calibration);
    result = std::async(std::launch::async, [this] { return calibration.compute(); });
    held.started.get_future().wait();
  }
};

}  // namespace

TEST_CASE("LOCATE's geometry and STATUS's summary answer while a COMPUTE runs",
          "[vision_app][calibration]") {
  test::TempDir dir;
  HeldCompute computing(dir);
  CellCalibration& c = computing.calibration;
  // The fit is running and holds nothing these need: they return now.
  auto geometry = c.geometry();
  REQUIRE(geometry);
  CHECK(geometry->frame() == CoordinateFrame::kVisionPixels);
  CHECK(c.summary().points == 4);
  CHECK(c.points().size() == 4);
  computing.held.release.set_value();
  auto result = computing.result.get();
  REQUIRE(result);
  CHECK(result->transform.rz_deg == Approx(90).margin(1e-6));
  CHECK(c.geometry()->frame() == CoordinateFrame::kRobot);
}

TEST_CASE("a STORE during a COMPUTE makes it refuse its stale result",
          "[vision_app][calibration]") {
  test::TempDir dir;
  HeldCompute computing(dir);
  CellCalibration& c = computing.calibration;
  REQUIRE(c.addPoint(pointAt(20, 15)));
  computing.held.release.set_value();
  auto result = computing.result.get();
  REQUIRE_FALSE(result);
  CHECK(result.error().code == CellCalibrationErrc::kPointsChanged);
  CHECK_FALSE(c.summary().transform);
}

TEST_CASE("stored points have a cap and a clear error past it", "[vision_app][calibration]") {
  test::TempDir dir;
  CellCalibration c(dir.file("calibration.yaml"));
  REQUIRE(c.load());
  for (size_t i = 0; i < CellCalibration::kMaxPoints; ++i) {
    REQUIRE(c.addPoint(pointAt(static_cast<double>(i % 16), static_cast<double>(i / 16))));
  }
  auto refused = c.addPoint(pointAt(1000, 1000));
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == CellCalibrationErrc::kTooManyPoints);
  CHECK(refused.error().message.find("256") != std::string::npos);
  CHECK(c.summary().points == CellCalibration::kMaxPoints);
  REQUIRE(c.deletePoint(1));
  CHECK(c.addPoint(pointAt(1000, 1000)));
}

TEST_CASE("non-finite points are refused", "[vision_app][calibration]") {
  test::TempDir dir;
  CellCalibration c(dir.file("calibration.yaml"));
  REQUIRE(c.load());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  CHECK_FALSE(c.addPoint({{nan, 0}, {0, 0}}));
  CHECK_FALSE(c.addPoint({{0, 0}, {0, inf}}));
  CHECK(c.summary().points == 0);
}

TEST_CASE("a damaged calibration file blocks the geometry until cleared",
          "[vision_app][calibration]") {
  test::TempDir dir;
  const std::string path = dir.write("calibration.yaml", "format_version: [unclosed\n");
  CellCalibration c(path);
  auto loaded = c.load();
  REQUIRE_FALSE(loaded);
  REQUIRE(c.damage());
  auto geometry = c.geometry();
  REQUIRE_FALSE(geometry);
  CHECK(geometry.error().code == CellCalibrationErrc::kDamaged);
  CHECK(geometry.error().message.find("CLEARCAL") != std::string::npos);
  auto refused = c.addPoint(pointAt(0, 0));
  REQUIRE_FALSE(refused);
  CHECK(refused.error().code == CellCalibrationErrc::kDamaged);
  CHECK_FALSE(c.compute());

  REQUIRE(c.clear());
  CHECK_FALSE(c.damage());
  REQUIRE(c.geometry());
  CHECK(c.geometry()->frame() == CoordinateFrame::kVisionPixels);
  // The damaged file is kept beside, for whoever wants to repair it.
  CHECK(std::filesystem::exists(path + ".damaged"));
  CHECK_FALSE(std::filesystem::exists(path));
  CHECK(c.addPoint(pointAt(0, 0)));
}

TEST_CASE("a calibration file with a non-finite number is damaged, not loaded",
          "[vision_app][calibration]") {
  test::TempDir dir;
  const std::string path = dir.file("calibration.yaml");
  {
    CellCalibration good(path);
    REQUIRE(good.load());
    storeSquare(good);
    REQUIRE(good.compute());
  }
  auto text = readFile(path);
  REQUIRE(text);
  // The transform's x offset becomes NaN, as a hand edit or a bit flip might.
  const std::string damaged = std::regex_replace(*text, std::regex("dx: [-0-9.e+]+"), "dx: .nan");
  REQUIRE(damaged != *text);
  REQUIRE(writeFileAtomically(path, damaged));
  CellCalibration c(path);
  CHECK_FALSE(c.load());
  REQUIRE_FALSE(c.geometry());
  CHECK(c.geometry().error().code == CellCalibrationErrc::kDamaged);
  CHECK(c.summary().points == 0);  // nothing of it is used
  REQUIRE(c.clear());
  CHECK(c.geometry());
  CHECK(std::filesystem::exists(path + ".damaged"));
}

TEST_CASE("clearing a sound calibration removes its file", "[vision_app][calibration]") {
  test::TempDir dir;
  const std::string path = dir.file("calibration.yaml");
  CellCalibration c(path);
  REQUIRE(c.load());
  storeSquare(c);
  REQUIRE(std::filesystem::exists(path));
  REQUIRE(c.clear());
  CHECK_FALSE(std::filesystem::exists(path));
  CHECK(c.summary().points == 0);
  CHECK(c.clear());  // nothing to clear is fine
}

TEST_CASE("Temporaries of an interrupted calibration write are removed at load", "[vision_app]") {
  test::TempDir dir;
  const std::string path = dir.file("calibration.yaml");
  {
    CellCalibration c(path);
    REQUIRE(c.load());
    storeSquare(c);
  }
  const std::string before = *readFile(path);
  // What a process killed between its write and its rename leaves behind.
  std::FILE* torn = std::fopen((path + ".tmp.4242").c_str(), "w");
  REQUIRE(torn);
  std::fputs("format_version: 2\npoints:\n  - id: 1\n    vis", torn);
  std::fclose(torn);
  CellCalibration c(path);
  REQUIRE(c.load());
  CHECK_FALSE(std::filesystem::exists(path + ".tmp.4242"));
  CHECK(*readFile(path) == before);
  CHECK(c.points().size() == 4);
}
