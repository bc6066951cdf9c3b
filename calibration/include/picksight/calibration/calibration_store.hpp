// Calibration data that must survive restarts: the robot-camera point pairs
// (with their ids), the computed transform, the camera scale and the lens
// model. One human-readable file in the data directory, replaced
// atomically on every change, so a crash mid-write loses nothing.
//
// Threading: not thread-safe; its owner serializes access.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>

#include "picksight/calibration/camera_calibration.hpp"
#include "picksight/calibration/robot_camera.hpp"
#include "picksight/common/result.hpp"

namespace picksight::calibration {

struct StoredPoint {
  int id = 0;
  PointPair pair;
};

class CalibrationStore {
 public:
  // Uses `path` (e.g. <data-dir>/calibration.yaml); call load() next.
  explicit CalibrationStore(std::string path);

  // Reads the file if it exists. A damaged file is an error naming the file
  // and the problem; the store then stays empty and the file is left alone.
  Result<void> load();

  // The new id. `pixel`: the sensor pixel the vision point was measured at,
  // kept so that the vision point can be derived again with a later camera
  // scale or lens model.
  Result<int> addPoint(const PointPair& pair, std::optional<cv::Point2d> pixel = std::nullopt);
  Result<void> deletePoint(int id);  // error names the missing id
  const std::map<int, PointPair>& points() const { return points_; }
  // Sensor pixels of the points stored with one (by id).
  const std::map<int, cv::Point2d>& pixels() const { return pixels_; }

  Result<void> setTransform(const CalibrationResult& result);
  const std::optional<CalibrationResult>& transform() const { return transform_; }

  Result<void> setScale(const PixelScale& scale);
  const std::optional<PixelScale>& scale() const { return scale_; }

  Result<void> setLens(const LensModel& lens);
  const std::optional<LensModel>& lens() const { return lens_; }

  // The scale and, when given, the lens model in one write: the file holds
  // both or, when the write fails, neither (the lens kept when not given).
  Result<void> setScaleAndLens(const PixelScale& scale, const std::optional<LensModel>& lens);

  const std::string& path() const { return path_; }

 private:
  // Applies `edit` to a copy, writes the copy, and only then keeps it.
  Result<void> change(const std::function<void(CalibrationStore&)>& edit);
  Result<void> save();
  std::string serialize() const;

  std::string path_;
  std::map<int, PointPair> points_;
  std::map<int, cv::Point2d> pixels_;
  int next_id_ = 1;
  std::optional<CalibrationResult> transform_;
  std::optional<PixelScale> scale_;
  std::optional<LensModel> lens_;
};

}  // namespace picksight::calibration
