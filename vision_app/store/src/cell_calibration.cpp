// Cell calibration: the calibration store behind a lock, and the reply frame.
#include "picksight/store/cell_calibration.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "picksight/common/atomic_file.hpp"
#include "picksight/common/log.hpp"

namespace picksight::store {

const char* errorName(CellCalibrationErrc e) {
  switch (e) {
    case CellCalibrationErrc::kNoSuchPoint:
      return "no such point";
    case CellCalibrationErrc::kCalibrationStorage:
      return "calibration storage";
    case CellCalibrationErrc::kNotComputed:
      return "not computed";
    case CellCalibrationErrc::kDamaged:
      return "damaged";
    case CellCalibrationErrc::kTooManyPoints:
      return "too many points";
    case CellCalibrationErrc::kPointsChanged:
      return "points changed";
  }
  return "unknown";
}
namespace {
Error storageError(const Error& e) {
  return makeError(CellCalibrationErrc::kCalibrationStorage,
                   "cannot write the calibration: " + e.message);
}

bool finite(cv::Point2d p) { return std::isfinite(p.x) && std::isfinite(p.y); }

// The geometry of a loaded store. The lens model applies wherever it
// exists, with or without a scale.
CellGeometry geometryOf(const calibration::CalibrationStore& store) {
  CellGeometry g;
  g.vision = store.scale() ? calibration::VisionFrame(*store.scale(), store.lens())
                           : calibration::VisionFrame::pixels(store.lens());
  if (store.transform()) g.transform = store.transform()->transform;
  return g;
}

// The stored points as the fit sees them: a point stored with its sensor
// pixel is placed again through the current scale and lens model (a CALCAM
// or lens calibration after STORE then needs no new STORE); older points
// keep the vision coordinates they were stored with.
std::map<int, calibration::PointPair> currentPoints(const calibration::CalibrationStore& store) {
  std::map<int, calibration::PointPair> out = store.points();
  const calibration::VisionFrame vision = geometryOf(store).vision;
  for (const auto& [id, pixel] : store.pixels()) {
    if (auto p = out.find(id); p != out.end()) p->second.vision = vision.toMm(pixel);
  }
  return out;
}

// Why a loaded store cannot be used, or empty. Checked through what LOCATE
// computes (the frame conversions at a few points across a large sensor)
// rather than field by field, so a non-finite value anywhere in the scale,
// the lens or the transform is caught whatever their form.
std::string unusable(const calibration::CalibrationStore& store) {
  for (const auto& [id, pair] : currentPoints(store)) {
    if (!finite(pair.vision) || !finite(pair.robot)) {
      return "point " + std::to_string(id) + " has a non-finite coordinate";
    }
  }
  if (store.transform() && !std::isfinite(store.transform()->rms)) {
    return "its transform has a non-finite RMS";
  }
  const CellGeometry g = geometryOf(store);
  for (const cv::Point2d pixel :
       {cv::Point2d(0, 0), cv::Point2d(4000, 0), cv::Point2d(0, 3000), cv::Point2d(4000, 3000)}) {
    const cv::Point2d mm = g.vision.toMm(pixel);
    const grasp::Pose reply = g.toReply({mm.x, mm.y, 30});
    if (!finite(mm) || !std::isfinite(reply.x) || !std::isfinite(reply.y) ||
        !std::isfinite(reply.rz_deg)) {
      return "its scale, lens model or transform gives non-finite coordinates";
    }
  }
  return {};
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

CellCalibration::CellCalibration(std::string path, Fit fit)
    : fit_(std::move(fit)), store_(std::move(path)) {}

Result<void> CellCalibration::check(const std::string& staged) {
  calibration::CalibrationStore store(staged);
  if (auto ok = store.load(); !ok)
    return makeError(CellCalibrationErrc::kDamaged, ok.error().message);
  if (const std::string why = unusable(store); !why.empty())
    return makeError(CellCalibrationErrc::kDamaged, staged + ": " + why);
  return {};
}

Result<void> CellCalibration::adopt(const std::optional<std::string>& staged) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string path = store_.path();
  std::error_code ec;
  if (staged) {
    std::filesystem::rename(*staged, path, ec);
  } else {
    std::filesystem::remove(path, ec);
  }
  if (ec) return makeError(CellCalibrationErrc::kCalibrationStorage, path + ": " + ec.message());
  ++revision_;
  calibration::CalibrationStore fresh(path);
  auto ok = fresh.load();
  damaged_ = ok ? std::string() : ok.error().message;
  store_ = std::move(fresh);
  if (!ok) return makeError(CellCalibrationErrc::kDamaged, damaged_);
  return {};
}

Result<std::optional<std::string>> CellCalibration::fileText() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!damaged_.empty()) return blocked();
  std::error_code ec;
  if (!std::filesystem::exists(store_.path(), ec)) return std::optional<std::string>();
  auto text = readFile(store_.path());
  if (!text) return makeError(CellCalibrationErrc::kCalibrationStorage, text.error().message);
  return std::optional<std::string>(std::move(*text));
}

Result<void> CellCalibration::load() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++revision_;
  // Left by a write that a crash interrupted; this process owns the data
  // directory (the models/ directory is cleaned by the model library).
  const std::string directory = std::filesystem::path(store_.path()).parent_path().string();
  if (auto removed = removeStaleTemporaries(directory.empty() ? "." : directory)) {
    for (const auto& name : *removed) {
      logInfo(directory, ": removed ", name, " (left by an interrupted write)");
    }
  } else {
    logError(removed.error().message);
  }
  auto ok = store_.load();
  damaged_ = ok ? std::string() : ok.error().message;
  if (ok) {
    if (const std::string why = unusable(store_); !why.empty()) {
      damaged_ = store_.path() + ": " + why;
      store_ = calibration::CalibrationStore(store_.path());  // nothing of it is used
      return makeError(CellCalibrationErrc::kDamaged, damaged_);
    }
  }
  return ok;
}

std::optional<std::string> CellCalibration::damage() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (damaged_.empty()) return std::nullopt;
  return damaged_;
}

Result<void> CellCalibration::clear() {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string& path = store_.path();
  // A damaged file is kept for whoever wants to repair it; a sound one goes.
  const bool keep = !damaged_.empty();
  const int failed =
      keep ? std::rename(path.c_str(), (path + ".damaged").c_str()) : std::remove(path.c_str());
  if (failed != 0 && errno != ENOENT) {
    return storageError(
        systemError(errno, keep ? "cannot rename " + path : "cannot remove " + path));
  }
  const std::string dir = std::filesystem::path(path).parent_path().string();
  if (auto ok = syncDirectory(dir.empty() ? "." : dir); !ok) return storageError(ok.error());
  store_ = calibration::CalibrationStore(path);
  damaged_.clear();
  ++revision_;
  return {};
}

Error CellCalibration::blocked() const {
  return makeError(CellCalibrationErrc::kDamaged, "the calibration file is damaged (" +
                                                      damaged_.substr(0, 200) +
                                                      "): repair it and restart, or CLEARCAL");
}

Result<CellGeometry> CellCalibration::geometry() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!damaged_.empty()) return blocked();
  return geometryOf(store_);
}

CalibrationSummary CellCalibration::summary() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return {store_.scale(), store_.lens().has_value(), store_.points().size(), store_.transform()};
}

std::map<int, calibration::PointPair> CellCalibration::points() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return currentPoints(store_);
}

Result<void> CellCalibration::setScale(const calibration::PixelScale& scale) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!damaged_.empty()) return blocked();
  auto ok = store_.setScale(scale);
  if (!ok) return storageError(ok.error());
  ++revision_;
  return {};
}

Result<void> CellCalibration::setLens(const calibration::LensModel& lens) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!damaged_.empty()) return blocked();
  auto ok = store_.setLens(lens);
  if (!ok) return storageError(ok.error());
  ++revision_;
  return {};
}

Result<void> CellCalibration::setGridCalibration(
    const calibration::PixelScale& scale, const std::optional<calibration::LensModel>& lens) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!damaged_.empty()) return blocked();
  // One write: a failure leaves the file, and the calibration in use, as
  // they were, never a new lens with the old scale.
  auto ok = store_.setScaleAndLens(scale, lens);
  if (!ok) return storageError(ok.error());
  ++revision_;
  return {};
}

std::optional<calibration::LensModel> CellCalibration::lens() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return store_.lens();
}

Result<int> CellCalibration::addPoint(const calibration::PointPair& pair,
                                      std::optional<cv::Point2d> pixel) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!damaged_.empty()) return blocked();
  if (!finite(pair.vision) || !finite(pair.robot) || (pixel && !finite(*pixel))) {
    return makeError(calibration::CalibrationErrc::kBadInput, "a point must be finite");
  }
  if (store_.points().size() >= kMaxPoints) {
    return makeError(CellCalibrationErrc::kTooManyPoints,
                     std::to_string(kMaxPoints) + " points are stored already (DELETE some)");
  }
  auto id = store_.addPoint(pair, pixel);
  if (!id) return storageError(id.error());
  ++revision_;
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
  ++revision_;
  return {};
}

Result<calibration::CalibrationResult> CellCalibration::compute(calibration::Method method) {
  std::vector<calibration::PointPair> pairs;
  uint64_t revision = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!damaged_.empty()) return blocked();
    for (const auto& [id, pair] : currentPoints(store_)) pairs.push_back(pair);
    revision = revision_;
  }
  // The fit may take long with many points: LOCATE and STATUS go on meanwhile.
  auto result = fit_ ? fit_(pairs, method) : calibration::calibrate(pairs, method);
  if (!result) return result.error();
  std::lock_guard<std::mutex> lock(mutex_);
  if (!damaged_.empty()) return blocked();
  if (revision_ != revision) {
    return makeError(CellCalibrationErrc::kPointsChanged,
                     "the points or the scale changed while COMPUTE ran; COMPUTE again");
  }
  auto ok = store_.setTransform(*result);
  if (!ok) return storageError(ok.error());
  return result;
}

}  // namespace picksight::store
