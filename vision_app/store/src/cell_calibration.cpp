// Cell calibration: the calibration store behind a lock, and the reply frame.
#include "picksight/store/cell_calibration.hpp"

#include <vector>

namespace picksight::app {

const char* errorName(CellCalibrationErrc e) {
  switch (e) {
    case CellCalibrationErrc::kNoSuchPoint:
      return "no such point";
    case CellCalibrationErrc::kCalibrationStorage:
      return "calibration storage";
    case CellCalibrationErrc::kNotComputed:
      return "not computed";
  }
  return "unknown";
}
namespace {
Error storageError(const Error& e) {
  return makeError(CellCalibrationErrc::kCalibrationStorage,
                   "cannot write the calibration: " + e.message);
}
}  // namespace

const char* frameName(CoordinateFrame frame) {
  switch (frame) {
    case CoordinateFrame::kVisionPixels:
      return "vision-px";
    case CoordinateFrame::kVisionMm:
      return "vision-mm";
    case CoordinateFrame::kRobot:
      return "robot";
  }
  return "?";
}

CoordinateFrame CellGeometry::frame() const {
  if (transform) return CoordinateFrame::kRobot;
  return vision.calibrated() ? CoordinateFrame::kVisionMm : CoordinateFrame::kVisionPixels;
}

grasp::Pose CellGeometry::toReply(const grasp::Pose& p) const {
  if (!transform) return p;
  const cv::Point2d r = transform->apply({p.x, p.y});
  return {r.x, r.y, transform->applyToAngleDeg(p.rz_deg, {p.x, p.y})};
}

CellCalibration::CellCalibration(std::string path) : store_(std::move(path)) {}

Result<void> CellCalibration::load() {
  std::lock_guard<std::mutex> lock(mutex_);
  auto ok = store_.load();
  damaged_ = ok ? std::string() : ok.error().message;
  return ok;
}

Error CellCalibration::blocked() const {
  return makeError(
      CellCalibrationErrc::kCalibrationStorage,
      "the calibration file is damaged, nothing is changed: " + damaged_.substr(0, 200));
}

CellGeometry CellCalibration::geometry() const {
  std::lock_guard<std::mutex> lock(mutex_);
  CellGeometry g;
  if (store_.scale()) g.vision = calibration::VisionFrame(*store_.scale(), store_.lens());
  if (store_.transform()) g.transform = store_.transform()->transform;
  return g;
}

CalibrationSummary CellCalibration::summary() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return {store_.scale(), store_.lens().has_value(), store_.points().size(), store_.transform()};
}

std::map<int, calibration::PointPair> CellCalibration::points() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return store_.points();
}

Result<void> CellCalibration::setScale(const calibration::PixelScale& scale) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!damaged_.empty()) return blocked();
  auto ok = store_.setScale(scale);
  if (!ok) return storageError(ok.error());
  return {};
}

Result<void> CellCalibration::setLens(const calibration::LensModel& lens) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!damaged_.empty()) return blocked();
  auto ok = store_.setLens(lens);
  if (!ok) return storageError(ok.error());
  return {};
}

Result<int> CellCalibration::addPoint(const calibration::PointPair& pair) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!damaged_.empty()) return blocked();
  auto id = store_.addPoint(pair);
  if (!id) return storageError(id.error());
  return id;
}

Result<void> CellCalibration::deletePoint(int id) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!damaged_.empty()) return blocked();
  if (!store_.points().count(id))
    return makeError(CellCalibrationErrc::kNoSuchPoint,
                     "no point with id " + std::to_string(id) + " (see LIST)");
  auto ok = store_.deletePoint(id);
  if (!ok) return storageError(ok.error());
  return {};
}

Result<calibration::CalibrationResult> CellCalibration::compute(calibration::Method method) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!damaged_.empty()) return blocked();
  std::vector<calibration::PointPair> pairs;
  for (const auto& [id, pair] : store_.points()) pairs.push_back(pair);
  auto result = calibration::calibrate(pairs, method);
  if (!result) return result.error();
  auto ok = store_.setTransform(*result);
  if (!ok) return storageError(ok.error());
  return result;
}

}  // namespace picksight::app
