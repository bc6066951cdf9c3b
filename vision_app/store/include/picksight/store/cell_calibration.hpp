// The cell's calibration as the robot protocol sees it: the camera scale
// (CALCAM), the lens model (applied to every pixel: stored points and
// located parts), the robot-camera point pairs (STORE, DELETE,
// LIST) and transform (COMPUTE), persisted in <data dir>/calibration.yaml,
// and the coordinate frame LOCATE replies in, which follows from them.
//
// Threading: every member is thread-safe; geometry() returns a copy, so a
// LOCATE in progress keeps the calibration it started with. compute() fits
// on a copy of the points without holding the lock geometry() and
// summary() take: a long COMPUTE never delays a LOCATE or a STATUS.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "picksight/calibration/calibration_store.hpp"
#include "picksight/calibration/vision_frame.hpp"
#include "picksight/common/result.hpp"
#include "picksight/grasp/grasp.hpp"

namespace picksight::store {

// Why a change to the cell's calibration failed. (COMPUTE's own failures
// are calibration::CalibrationErrc, passed on as they are.)
enum class CellCalibrationErrc {
  kNoSuchPoint = 1,     // DELETE: no point with that id
  kCalibrationStorage,  // calibration.yaml could not be written, or is damaged
  kNotComputed,         // no robot-camera transform yet
  kDamaged,             // calibration.yaml exists but cannot be used: see CLEARCAL
  kTooManyPoints,       // STORE: kMaxPoints are stored already
  kPointsChanged,       // COMPUTE: a STORE or DELETE came while it computed
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
  // At most this many stored points: COMPUTE's time and the file's size stay
  // bounded, and a robot program stuck in a STORE loop is told so.
  static constexpr size_t kMaxPoints = 256;

  // How COMPUTE fits; calibration::calibrate unless a test puts a fit it
  // controls in its place (to hold a COMPUTE in progress).
  using Fit = std::function<Result<calibration::CalibrationResult>(
      const std::vector<calibration::PointPair>&, calibration::Method)>;

  explicit CellCalibration(std::string path, Fit fit = {});

  // Reads the file if it exists. A file that exists but cannot be used
  // (unreadable, unparsable, or giving non-finite coordinates) is an error
  // and is left alone: until it is repaired and loaded again, or clear()
  // is called, geometry() and every change are refused
  // (CellCalibrationErrc::kDamaged), so that LOCATE never silently replies
  // in another frame and nothing an integrator may still repair is
  // overwritten.
  Result<void> load();
  // Why the file could not be used; nullopt when it is sound (or absent).
  std::optional<std::string> damage() const;
  // Forgets the whole calibration (scale, lens, points, transform). A
  // damaged file is kept beside, renamed to <path>.damaged; a sound one is
  // removed. LOCATE then replies in vision pixels.
  Result<void> clear();

  // The geometry LOCATE replies with; kDamaged while the file is damaged.
  Result<CellGeometry> geometry() const;
  CalibrationSummary summary() const;
  // The stored points with their vision coordinates as COMPUTE fits them:
  // those stored with a sensor pixel through the current scale and lens model.
  std::map<int, calibration::PointPair> points() const;

  // Each change is written before it takes effect (CellCalibrationErrc::kCalibrationStorage).
  Result<void> setScale(const calibration::PixelScale& scale);
  Result<void> setLens(const calibration::LensModel& lens);
  // A dot grid's scale (with its rectification) and, when fitted, its lens
  // model (else the stored lens is kept), under one lock and in one write:
  // no request sees one without the other, and a failed write changes
  // neither.
  Result<void> setGridCalibration(const calibration::PixelScale& scale,
                                  const std::optional<calibration::LensModel>& lens);
  std::optional<calibration::LensModel> lens() const;
  // Refuses non-finite coordinates, and a point past kMaxPoints. `pixel`:
  // the sensor pixel `pair.vision` was measured at (STORE), so that a later
  // CALCAM or lens model places the point again.
  Result<int> addPoint(const calibration::PointPair& pair,
                       std::optional<cv::Point2d> pixel = std::nullopt);
  Result<void> deletePoint(int id);  // CellCalibrationErrc::kNoSuchPoint names the id
  // Fits the transform to a copy of the stored points, outside the lock,
  // and stores it, unless a STORE or DELETE came meanwhile (kPointsChanged).
  Result<calibration::CalibrationResult> compute(
      calibration::Method method = calibration::Method::kBest);

  const std::string& path() const { return store_.path(); }

  // JOB LOAD. check(): whether a calibration file at `staged` can be used
  // (kDamaged names what is wrong), read without touching the cell's.
  static Result<void> check(const std::string& staged);
  // Puts the checked file `staged` in place of the cell's (rename; the
  // caller syncs the directory) and in force, or with nullopt removes the
  // cell's: LOCATE then replies in vision pixels. A COMPUTE under way is
  // refused (kPointsChanged).
  Result<void> adopt(const std::optional<std::string>& staged);
  // The file's text as stored (JOB SAVE); nullopt when there is none.
  // kDamaged while the file is damaged.
  Result<std::optional<std::string>> fileText() const;

 private:
  Error blocked() const;

  const Fit fit_;
  mutable std::mutex mutex_;  // guards store_, damaged_ and revision_
  calibration::CalibrationStore store_;
  std::string damaged_;    // why load() failed; empty when writable
  uint64_t revision_ = 0;  // counts changes to the points and the scale
};

}  // namespace picksight::store

PICKSIGHT_ERROR_ENUM(picksight::store::CellCalibrationErrc)
