// The cell's calibration as the robot protocol sees it: the camera scale
// (CALCAM), the lens model, the robot-camera point pairs (STORE, DELETE,
// LIST) and transform (COMPUTE), persisted in <data dir>/calibration.yaml,
// and the coordinate frame LOCATE replies in, which follows from them.
//
// Threading: every member is thread-safe; geometry() returns a copy, so a
// LOCATE in progress keeps the calibration it started with.
#pragma once

#include <map>
#include <mutex>
#include <optional>
#include <string>

#include "picksight/calibration/calibration_store.hpp"
#include "picksight/calibration/vision_frame.hpp"
#include "picksight/common/result.hpp"
#include "picksight/grasp/grasp.hpp"

namespace picksight::app {

// Why a change to the cell's calibration failed. (COMPUTE's own failures
// are calibration::CalibrationErrc, passed on as they are.)
enum class CellCalibrationErrc {
  kNoSuchPoint = 1,     // DELETE: no point with that id
  kCalibrationStorage,  // calibration.yaml could not be written, or is damaged
  kNotComputed,         // no robot-camera transform yet
};
const char* errorName(CellCalibrationErrc e);
PICKSIGHT_ERROR_DOMAIN(CellCalibrationErrc, "cell calibration")

// The frame LOCATE replies in: the vision frame in sensor pixels (no
// CALCAM), in millimetres (CALCAM, no COMPUTE), or the robot frame.
enum class CoordinateFrame { kVisionPixels, kVisionMm, kRobot };
const char* frameName(CoordinateFrame frame);  // "vision-px", "vision-mm", "robot"

// Everything needed to turn sensor pixels into reply poses.
struct CellGeometry {
  calibration::VisionFrame vision;  // 1 unit per pixel until CALCAM
  std::optional<calibration::PlaneTransform> transform;

  CoordinateFrame frame() const;
  // A pose in the vision frame to the reply frame (robot when computed).
  grasp::Pose toReply(const grasp::Pose& vision_pose) const;
};

struct CalibrationSummary {
  std::optional<calibration::PixelScale> scale;
  bool lens = false;
  size_t points = 0;
  std::optional<calibration::CalibrationResult> transform;
};

class CellCalibration {
 public:
  explicit CellCalibration(std::string path);

  // Reads the file if it exists. A damaged file is an error, and is left
  // alone: every change is then refused (CellCalibrationErrc::kCalibrationStorage) rather than
  // overwrite what an integrator may still repair.
  Result<void> load();

  CellGeometry geometry() const;
  CalibrationSummary summary() const;
  std::map<int, calibration::PointPair> points() const;

  // Each change is written before it takes effect (CellCalibrationErrc::kCalibrationStorage).
  Result<void> setScale(const calibration::PixelScale& scale);
  Result<void> setLens(const calibration::LensModel& lens);
  Result<int> addPoint(const calibration::PointPair& pair);
  Result<void> deletePoint(int id);  // CellCalibrationErrc::kNoSuchPoint names the id
  // Fits the transform to the stored points and stores it.
  Result<calibration::CalibrationResult> compute(
      calibration::Method method = calibration::Method::kBest);

  const std::string& path() const { return store_.path(); }

 private:
  Error blocked() const;

  mutable std::mutex mutex_;  // guards store_ and damaged_
  calibration::CalibrationStore store_;
  std::string damaged_;  // why load() failed; empty when writable
};

}  // namespace picksight::app

PICKSIGHT_ERROR_ENUM(picksight::app::CellCalibrationErrc)
