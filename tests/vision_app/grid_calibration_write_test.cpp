// CALCAM GRID's calibration (scale with its rectification, lens model) is
// stored in one atomic write: the file then holds both, and a write that
// fails leaves the file and the calibration in use as they were.
#include <catch2/catch.hpp>

#include <sys/inotify.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "picksight/common/atomic_file.hpp"
#include "picksight/store/cell_calibration.hpp"
#include "temp_dir.hpp"

using namespace picksight;
using namespace picksight::store;

namespace {
calibration::PixelScale gridScale(double mm_per_px) {
  calibration::PixelScale s;
  s.mm_per_px_x = mm_per_px;
  s.mm_per_px_y = mm_per_px * 1.001;
  s.rectify = cv::Matx33d(1, 0.001, 0, 0, 1, 0, 1e-6, 0, 1);
  return s;
}

calibration::LensModel gridLens(double k1) {
  calibration::LensModel lens;
  lens.image_size = {1280, 960};
  lens.camera_matrix = cv::Matx33d(1500, 0, 640, 0, 1500, 480, 0, 0, 1);
  lens.distortion = {k1, 0.01, 0, 0, 0};
  lens.rms_reprojection_px = 0.05;
  lens.views = 1;
  return lens;
}

// Counts the files renamed into a directory (what an atomic write's last
// step does) from the moment it is built.
class Renames {
 public:
  explicit Renames(const std::string& directory) : fd_(inotify_init1(IN_NONBLOCK | IN_CLOEXEC)) {
    REQUIRE(fd_ >= 0);
    // Creations too: the kernel merges an event with an identical one
    // queued just before it, and two writes' renames alone would be one.
    REQUIRE(inotify_add_watch(fd_, directory.c_str(), IN_CREATE | IN_MOVED_TO) >= 0);
  }
  ~Renames() { ::close(fd_); }
  Renames(const Renames&) = delete;
  Renames& operator=(const Renames&) = delete;

  // The renames onto `name` queued so far (the kernel queues an event
  // before rename() returns: nothing to wait for).
  int onto(const std::string& name) {
    int n = 0;
    alignas(inotify_event) char buffer[4096];
    for (ssize_t got; (got = ::read(fd_, buffer, sizeof buffer)) > 0;) {
      for (ssize_t at = 0; at < got;) {
        const auto* event = reinterpret_cast<const inotify_event*>(buffer + at);
        if ((event->mask & IN_MOVED_TO) && event->len > 0 && name == event->name) ++n;
        at += static_cast<ssize_t>(sizeof(inotify_event) + event->len);
      }
    }
    return n;
  }

 private:
  int fd_;
};
}  // namespace

TEST_CASE("a grid calibration is stored in one write holding scale and lens",
          "[calibration][atomic]") {
  const test::TempDir dir;
  const std::string path = dir.file("calibration.yaml");
  CellCalibration cell(path);
  REQUIRE(cell.load());
  Renames renames(dir.path().string());
  REQUIRE(cell.setGridCalibration(gridScale(0.25), gridLens(-0.1)));
  CHECK(renames.onto("calibration.yaml") == 1);

  CellCalibration reloaded(path);
  REQUIRE(reloaded.load());
  const CalibrationSummary s = reloaded.summary();
  REQUIRE(s.scale);
  CHECK(s.scale->mm_per_px_x == 0.25);
  REQUIRE(s.scale->rectify);
  CHECK(s.scale->rectify->val[1] == 0.001);
  REQUIRE(reloaded.lens());
  CHECK(reloaded.lens()->distortion[0] == -0.1);

  // A grid that fits no lens keeps the stored one, still in one write.
  REQUIRE(cell.setGridCalibration(gridScale(0.5), std::nullopt));
  CHECK(renames.onto("calibration.yaml") == 1);
  CellCalibration again(path);
  REQUIRE(again.load());
  REQUIRE(again.summary().scale);
  CHECK(again.summary().scale->mm_per_px_x == 0.5);
  REQUIRE(again.lens());
  CHECK(again.lens()->distortion[0] == -0.1);
}

TEST_CASE("a grid calibration whose write fails changes neither the file nor the calibration",
          "[calibration][atomic]") {
  const test::TempDir dir;
  const std::string path = dir.file("calibration.yaml");
  CellCalibration cell(path);
  REQUIRE(cell.load());
  REQUIRE(cell.setGridCalibration(gridScale(0.25), gridLens(-0.1)));
  const auto before = readFile(path);
  REQUIRE(before);

  // The write's temporary file cannot be created: a directory holds its
  // name (root included, unlike a read-only directory).
  const std::string temporary = path + ".tmp." + std::to_string(::getpid());
  REQUIRE(std::filesystem::create_directory(temporary));
  const auto failed = cell.setGridCalibration(gridScale(0.5), gridLens(-0.2));
  REQUIRE_FALSE(failed);
  CHECK(failed.error().code == CellCalibrationErrc::kCalibrationStorage);
  std::filesystem::remove(temporary);

  const auto after = readFile(path);
  REQUIRE(after);
  CHECK(*after == *before);
  REQUIRE(cell.summary().scale);
  CHECK(cell.summary().scale->mm_per_px_x == 0.25);
  REQUIRE(cell.lens());
  CHECK(cell.lens()->distortion[0] == -0.1);
}
