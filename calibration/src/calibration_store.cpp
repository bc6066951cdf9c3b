// Calibration persistence in YAML, written atomically. Every change is
// applied to a copy, saved, and only then kept: memory never says what the
// disk does not.
#include "picksight/calibration/calibration_store.hpp"

#include "picksight/calibration/calibration_errors.hpp"

#include <yaml-cpp/yaml.h>

#include <sys/stat.h>
#include <cerrno>
#include <cmath>
#include <string>
#include <vector>

#include "picksight/common/atomic_file.hpp"

namespace picksight::calibration {
namespace {
// Version 2 adds the transform's model (similarity, tilt, homography);
// version 1 files (rigid transforms) are still read.
constexpr int kFormatVersion = 2;

// A finite number under `key`; errors name the key with its section, since
// a NaN or an infinity read back would turn every LOCATE reply into one.
double number(const YAML::Node& node, const char* key, const std::string& where) {
  if (!node[key]) throw std::runtime_error("missing " + where + key);
  double v = 0;
  try {
    v = node[key].as<double>();
  } catch (const YAML::Exception&) {
    throw std::runtime_error(where + key + " is not a number");
  }
  if (!std::isfinite(v)) throw std::runtime_error(where + key + " is not a finite number");
  return v;
}

// A 3x3 matrix under `key`, row by row: nine finite numbers.
cv::Matx33d matrix(const YAML::Node& node, const char* key, const std::string& where) {
  if (!node[key]) throw std::runtime_error("missing " + where + key);
  std::vector<double> v;
  try {
    v = node[key].as<std::vector<double>>();
  } catch (const YAML::Exception&) {
    throw std::runtime_error(where + key + " is not a list of numbers");
  }
  if (v.size() != 9) throw std::runtime_error(where + key + " must have 9 values");
  cv::Matx33d m;
  for (size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) throw std::runtime_error(where + key + " is not all finite numbers");
    m.val[i] = v[i];
  }
  return m;
}

PlaneTransform transformFromYaml(const YAML::Node& t) {
  const std::string model = t["model"] ? t["model"].as<std::string>() : "rigid";
  const RigidTransform rigid{number(t, "dx", "transform."), number(t, "dy", "transform."),
                             number(t, "rz_deg", "transform."),
                             t["mirrored"] && t["mirrored"].as<bool>()};
  if (model == "rigid") return PlaneTransform::rigid(rigid);
  if (model == "similarity") {
    const double scale = number(t, "scale", "transform.");
    if (!(scale > 0)) throw std::runtime_error("transform.scale must be positive");
    return PlaneTransform::similarity(rigid, scale);
  }
  if (model == "homography" || model == "tilt") {
    auto p = PlaneTransform::homography(matrix(t, "matrix", "transform."));
    if (!p) throw std::runtime_error("transform.matrix: " + p.error().message);
    if (model == "tilt") p->model = TransformModel::kTilt;
    return *p;
  }
  throw std::runtime_error("transform.model must be rigid, similarity, tilt or homography");
}

Method methodFromName(const std::string& name) {
  for (Method m : {Method::kGeometric, Method::kLeastSquares, Method::kSimilarity, Method::kTilt,
                   Method::kHomography}) {
    if (name == methodName(m)) return m;
  }
  throw std::runtime_error("transform.method '" + name + "' is unknown");
}
}  // namespace

CalibrationStore::CalibrationStore(std::string path) : path_(std::move(path)) {}

std::string CalibrationStore::serialize() const {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << YAML::BeginMap;
  out << YAML::Key << "format_version" << YAML::Value << kFormatVersion;
  out << YAML::Key << "next_id" << YAML::Value << next_id_;
  out << YAML::Key << "points" << YAML::Value << YAML::BeginSeq;
  for (const auto& [id, p] : points_) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "id" << YAML::Value << id << YAML::Key
        << "vision_x" << YAML::Value << p.vision.x << YAML::Key << "vision_y" << YAML::Value
        << p.vision.y << YAML::Key << "robot_x" << YAML::Value << p.robot.x << YAML::Key
        << "robot_y" << YAML::Value << p.robot.y;
    if (const auto px = pixels_.find(id); px != pixels_.end()) {
      out << YAML::Key << "pixel_x" << YAML::Value << px->second.x << YAML::Key << "pixel_y"
          << YAML::Value << px->second.y;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  if (transform_) {
    const auto& t = transform_->transform;
    out << YAML::Key << "transform" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "dx" << YAML::Value << t.dx << YAML::Key << "dy" << YAML::Value << t.dy;
    out << YAML::Key << "rz_deg" << YAML::Value << t.rz_deg << YAML::Key << "mirrored"
        << YAML::Value << t.mirrored;
    out << YAML::Key << "model" << YAML::Value << modelName(t.model);
    out << YAML::Key << "scale" << YAML::Value << t.scale;
    if (t.model == TransformModel::kHomography || t.model == TransformModel::kTilt) {
      out << YAML::Key << "matrix" << YAML::Value << YAML::Flow << YAML::BeginSeq;
      for (int i = 0; i < 9; ++i) out << t.matrix.val[i];
      out << YAML::EndSeq;
    }
    out << YAML::Key << "method" << YAML::Value << methodName(transform_->method);
    out << YAML::Key << "rms" << YAML::Value << transform_->rms;
    out << YAML::Key << "inliers" << YAML::Value << transform_->inliers;
    out << YAML::EndMap;
  }
  if (scale_) {
    out << YAML::Key << "scale" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "mm_per_px_x" << YAML::Value << scale_->mm_per_px_x;
    out << YAML::Key << "mm_per_px_y" << YAML::Value << scale_->mm_per_px_y;
    out << YAML::Key << "skew_deg" << YAML::Value << scale_->skew_deg;
    if (scale_->rectify) {
      out << YAML::Key << "rectify" << YAML::Value << YAML::Flow << YAML::BeginSeq;
      for (int i = 0; i < 9; ++i) out << scale_->rectify->val[i];
      out << YAML::EndSeq;
    }
    out << YAML::EndMap;
  }
  if (lens_) {
    out << YAML::Key << "lens" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "image_width" << YAML::Value << lens_->image_size.width;
    out << YAML::Key << "image_height" << YAML::Value << lens_->image_size.height;
    out << YAML::Key << "camera_matrix" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (int i = 0; i < 9; ++i) out << lens_->camera_matrix(i / 3, i % 3);
    out << YAML::EndSeq;
    out << YAML::Key << "distortion" << YAML::Value << YAML::Flow << lens_->distortion;
    out << YAML::Key << "rms_reprojection_px" << YAML::Value << lens_->rms_reprojection_px;
    out << YAML::Key << "views" << YAML::Value << lens_->views;
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

Result<void> CalibrationStore::save() { return writeFileAtomically(path_, serialize()); }

Result<void> CalibrationStore::load() {
  struct stat st {};
  if (::stat(path_.c_str(), &st) != 0) return {};  // nothing stored yet
  CalibrationStore loaded(path_);
  try {
    const YAML::Node root = YAML::LoadFile(path_);
    if (!root.IsMap()) throw std::runtime_error("not a YAML map");
    const int version = root["format_version"] ? root["format_version"].as<int>() : 0;
    if (version < 1 || version > kFormatVersion) {
      throw std::runtime_error("format_version must be 1 to " + std::to_string(kFormatVersion));
    }
    loaded.next_id_ = root["next_id"] ? root["next_id"].as<int>() : 1;
    for (const auto& p : root["points"]) {
      const int id = p["id"].as<int>();
      if (id <= 0 || loaded.points_.count(id))
        throw std::runtime_error("bad or repeated point id " + std::to_string(id));
      const std::string where = "point " + std::to_string(id) + " ";
      loaded.points_[id] = PointPair{{number(p, "vision_x", where), number(p, "vision_y", where)},
                                     {number(p, "robot_x", where), number(p, "robot_y", where)}};
      if (p["pixel_x"] || p["pixel_y"])
        loaded.pixels_[id] = {number(p, "pixel_x", where), number(p, "pixel_y", where)};
      loaded.next_id_ = std::max(loaded.next_id_, id + 1);
    }
    if (const auto t = root["transform"]) {
      CalibrationResult r;
      r.transform = transformFromYaml(t);
      r.method = methodFromName(t["method"] ? t["method"].as<std::string>() : "lsq");
      r.rms = number(t, "rms", "transform.");
      r.inliers = t["inliers"] ? t["inliers"].as<int>() : 0;
      loaded.transform_ = r;
    }
    if (const auto s = root["scale"]) {
      PixelScale scale{number(s, "mm_per_px_x", "scale."), number(s, "mm_per_px_y", "scale."),
                       s["skew_deg"] ? number(s, "skew_deg", "scale.") : 0};
      if (!(scale.mm_per_px_x > 0) || !(scale.mm_per_px_y > 0))
        throw std::runtime_error("scale must be positive");
      if (s["rectify"]) {
        const cv::Matx33d h = matrix(s, "rectify", "scale.");
        if (!(std::abs(cv::determinant(h)) > 1e-12))
          throw std::runtime_error("scale.rectify is singular");
        scale.rectify = h;
      }
      loaded.scale_ = scale;
    }
    if (const auto l = root["lens"]) {
      LensModel lens;
      lens.image_size = cv::Size(l["image_width"].as<int>(), l["image_height"].as<int>());
      lens.camera_matrix = matrix(l, "camera_matrix", "lens.");
      lens.distortion = l["distortion"].as<std::vector<double>>();
      if (lens.distortion.size() < 4)
        throw std::runtime_error("lens distortion needs at least 4 values");
      for (double v : lens.distortion) {
        if (!std::isfinite(v)) throw std::runtime_error("lens.distortion is not all finite");
      }
      lens.rms_reprojection_px = number(l, "rms_reprojection_px", "lens.");
      lens.views = l["views"] ? l["views"].as<int>() : 0;
      loaded.lens_ = lens;
    }
  } catch (const std::exception& e) {
    return makeError(CalibrationErrc::kBadFile, path_ + ": " + e.what());
  }
  *this = std::move(loaded);
  return {};
}

Result<void> CalibrationStore::change(const std::function<void(CalibrationStore&)>& edit) {
  CalibrationStore next = *this;
  edit(next);
  if (auto ok = next.save(); !ok) return ok;
  *this = std::move(next);
  return {};
}

Result<int> CalibrationStore::addPoint(const PointPair& pair, std::optional<cv::Point2d> pixel) {
  const int id = next_id_;
  auto ok = change([&](CalibrationStore& next) {
    ++next.next_id_;
    next.points_[id] = pair;
    if (pixel) next.pixels_[id] = *pixel;
  });
  if (!ok) return ok.error();
  return id;
}

Result<void> CalibrationStore::deletePoint(int id) {
  if (!points_.count(id)) return systemError(ENOENT, "no point with id " + std::to_string(id));
  return change([&](CalibrationStore& next) {
    next.points_.erase(id);
    next.pixels_.erase(id);
  });
}

Result<void> CalibrationStore::setTransform(const CalibrationResult& result) {
  return change([&](CalibrationStore& next) { next.transform_ = result; });
}

Result<void> CalibrationStore::setScale(const PixelScale& scale) {
  return change([&](CalibrationStore& next) { next.scale_ = scale; });
}

Result<void> CalibrationStore::setLens(const LensModel& lens) {
  return change([&](CalibrationStore& next) { next.lens_ = lens; });
}

Result<void> CalibrationStore::setScaleAndLens(const PixelScale& scale,
                                               const std::optional<LensModel>& lens) {
  return change([&](CalibrationStore& next) {
    next.scale_ = scale;
    if (lens) next.lens_ = *lens;
  });
}

}  // namespace picksight::calibration
