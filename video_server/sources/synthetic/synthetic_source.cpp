// Synthetic camera source over the scene generator.
#include "synthetic_source.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "picksight/common/clock.hpp"
#include "picksight/common/text.hpp"

namespace picksight::video {
namespace {
constexpr int kMaxParts = 500;
}  // namespace

Result<SyntheticSourceOptions> parseSyntheticOptions(const std::string& text) {
  SyntheticSourceOptions o;
  for (auto field : splitFields(text, ",?&")) {
    const size_t eq = field.find('=');
    if (eq == std::string_view::npos) {
      return makeError(SourceErrc::kBadConfig,
                       "synthetic: expected key=value, got '" + std::string(field) + "'");
    }
    const std::string key(field.substr(0, eq));
    const std::string_view value = field.substr(eq + 1);
    const auto bad = [&](const std::string& what) {
      return makeError(SourceErrc::kBadConfig, "synthetic: " + key + " must be " + what +
                                                   ", got '" + std::string(value) + "'");
    };
    const auto integer = parseInt(value);
    const auto number = parseDouble(value);
    if (key == "width" || key == "height") {
      if (!integer || *integer < 64 || *integer > 16384) return bad("an integer in [64, 16384]");
      (key == "width" ? o.scene.width : o.scene.height) = static_cast<int>(*integer);
    } else if (key == "parts") {
      if (!integer || *integer < 0 || *integer > kMaxParts) return bad("an integer in [0, 500]");
      o.scene.parts = static_cast<int>(*integer);
    } else if (key == "seed") {
      if (!integer || *integer < 0) return bad("a non-negative integer");
      o.scene.seed = static_cast<uint64_t>(*integer);
    } else if (key == "noise") {
      if (!number || *number < 0 || *number > 100) return bad("a number in [0, 100]");
      o.scene.noise_sigma = *number;
    } else if (key == "size") {
      if (!number || *number < 8 || *number > 4000) return bad("a number in [8, 4000]");
      o.scene.part_size = *number;
    } else if (key == "light") {
      // A front light's scene: the parts on a textured surface, shaded,
      // beside their shadows, glossy, or faint (front_light.hpp); grey, as
      // this camera is.
      const std::string name(value);
      o.scene.front = {};
      if (name == "uneven" || name == "flat") {
        o.scene.uneven_light = name == "uneven";
      } else if (name == "clean" || name == "colour" ||
                 !synthetic::frontLightCondition(name, &o.scene.front, &o.scene.part_level,
                                                 &o.scene.background_level)) {
        return bad(
            "uneven, flat, or a front light: textured, shadow, glossy, low-contrast, wood "
            "or metal");
      } else {
        o.scene.uneven_light = true;
      }
    } else if (key == "types") {
      o.scene.types.clear();
      const auto& known = synthetic::allPartTypes();
      for (auto t : splitFields(value, "+")) {
        if (std::find(known.begin(), known.end(), t) == known.end()) {
          std::string names;
          for (const auto& k : known) names += (names.empty() ? "" : ", ") + k;
          return bad("part types joined by '+' among " + names);
        }
        o.scene.types.emplace_back(t);
      }
    } else if (key == "touching") {
      if (value != "0" && value != "1") return bad("0 or 1");
      o.scene.touching = value == "1";
    } else if (key == "blur") {
      if (!number || *number < 0 || *number > 20) return bad("a number in [0, 20]");
      o.scene.blur_sigma = *number;
    } else if (key == "mm_per_px") {
      if (!number || *number < 1e-4 || *number > 1000) return bad("a number in [0.0001, 1000]");
      o.robot.mm_per_px = *number;
    } else if (key == "rz") {
      if (!number || *number < -360 || *number > 360) return bad("a number in [-360, 360]");
      o.robot.rz_deg = *number;
    } else if (key == "dx" || key == "dy") {
      if (!number || std::abs(*number) > 1e6) return bad("a number in [-1e6, 1e6]");
      (key == "dx" ? o.robot.dx_mm : o.robot.dy_mm) = *number;
    } else if (key == "tilt_x" || key == "tilt_y") {
      if (!number || std::abs(*number) > 10) return bad("a number in [-10, 10]");
      (key == "tilt_x" ? o.robot.tilt_x_deg : o.robot.tilt_y_deg) = *number;
    } else if (key == "target") {
      if (value != "disc" && value != "grid") return bad("disc or grid");
      o.target.kind = value == "grid" ? synthetic::TargetKind::kGrid : synthetic::TargetKind::kDisc;
    } else if (key == "target_radius") {
      if (!number || *number <= 0 || *number > 10000) return bad("a number in (0, 10000]");
      o.target.radius_mm = *number;
    } else if (key == "grid") {
      const size_t x = value.find('x');
      const auto cols = parseInt(value.substr(0, x));
      const auto rows = x == std::string_view::npos ? std::nullopt : parseInt(value.substr(x + 1));
      if (!cols || !rows || *cols < 1 || *rows < 1 || *cols > 50 || *rows > 50) {
        return bad("COLSxROWS with 1 to 50 each");
      }
      o.target.cols = static_cast<int>(*cols);
      o.target.rows = static_cast<int>(*rows);
    } else if (key == "grid_pitch") {
      if (!number || *number <= 0 || *number > 10000) return bad("a number in (0, 10000]");
      o.target.pitch_mm = *number;
    } else if (key == "scene_every") {
      if (!integer || *integer < 0) return bad("a non-negative integer");
      o.scene_every = static_cast<uint64_t>(*integer);
    } else {
      return makeError(SourceErrc::kBadConfig,
                       "synthetic: unknown key '" + key +
                           "' (known: width, height, parts, seed, noise, size, light, types, "
                           "touching, blur, scene_every, mm_per_px, rz, dx, dy, tilt_x, tilt_y, "
                           "target, target_radius, grid, grid_pitch)");
    }
  }
  if (o.target.kind == synthetic::TargetKind::kGrid &&
      !(o.target.pitch_mm > 2 * o.target.radius_mm)) {
    return makeError(SourceErrc::kBadConfig,
                     "synthetic: grid_pitch must exceed twice target_radius (dots must not touch)");
  }
  return o;
}

SyntheticSource::SyntheticSource(SyntheticSourceOptions options) : options_(std::move(options)) {}

Result<void> SyntheticSource::open() {
  if (!renderer_) makeRenderer(layout_);
  return {};
}

SourceInfo SyntheticSource::info() const {
  SourceInfo i;
  i.vendor = "PickSight";
  i.model = "synthetic";
  i.serial = "seed-" + std::to_string(options_.scene.seed);
  i.sensor_width = options_.scene.width;
  i.sensor_height = options_.scene.height;
  i.formats = {"Mono8"};
  return i;
}

Result<SourceFrame> SyntheticSource::grab(std::chrono::milliseconds /*timeout*/) {
  if (!renderer_) return makeError(SourceErrc::kUnavailable, "synthetic source not open");
  if (options_.scene_every > 0) {
    const uint64_t layout = frame_index_ / options_.scene_every;
    if (layout != layout_) {
      makeRenderer(layout);
      layout_ = layout;
    }
  }
  SourceFrame frame;
  // Stamped when the exposure (the render) starts, as cameras stamp theirs:
  // the host timestamp, taken after the grab, then tells the render's length.
  frame.device_timestamp_ns = monotonicNs();
  cv::Mat& buffer = freeBuffer();
  renderer_->renderInto(frame_index_++, buffer);
  frame.image = buffer;
  frame.keepable = true;  // freeBuffer() never hands out a buffer still held
  for (const auto& p : renderer_->truth()) {
    frame.truth.push_back(TruthPart{p.type, p.x, p.y, p.angle_deg, p.symmetry_deg, p.area_px});
  }
  // Each dot of the target, as an isotropic part of type "target".
  for (const auto& d : renderer_->targetTruth()) {
    frame.truth.push_back(TruthPart{"target", d.image_px.x, d.image_px.y, 0, 0, d.area_px});
  }
  return frame;
}

Result<SimulatedRobot> SyntheticSource::moveTarget(std::optional<cv::Point2d> at_mm) {
  if (at_mm && !(std::isfinite(at_mm->x) && std::isfinite(at_mm->y) && std::abs(at_mm->x) <= 1e6 &&
                 std::abs(at_mm->y) <= 1e6)) {
    return makeError(SourceErrc::kBadValue, "target position must be finite, within 1e6 mm");
  }
  if (at_mm) {
    // A target the camera does not see whole is measured wrong (a cut disc's
    // centroid moves) or not at all: refused, as a real cell's robot program
    // would be told, and the target stays where it was.
    const int w = options_.scene.width;
    const int h = options_.scene.height;
    const synthetic::RobotCameraModel model(options_.robot, w, h);
    constexpr int kEdgePoints = 64;
    const double r = options_.target.radius_mm;
    for (const cv::Point2d& dot : synthetic::targetDots(options_.target, *at_mm)) {
      for (int i = 0; i < kEdgePoints; ++i) {
        const double t = 2 * M_PI * i / kEdgePoints;
        const cv::Point2d p = model.toImage(dot + r * cv::Point2d(std::cos(t), std::sin(t)));
        if (p.x >= -0.5 && p.y >= -0.5 && p.x <= w - 0.5 && p.y <= h - 0.5) continue;
        return makeError(SourceErrc::kBadValue,
                         "target at (" + formatFixed(at_mm->x) + ", " + formatFixed(at_mm->y) +
                             ") mm would lie outside the image (its edge at pixel (" +
                             formatFixed(p.x, 1) + ", " + formatFixed(p.y, 1) + "), the image is " +
                             std::to_string(w) + " x " + std::to_string(h) +
                             "): not moved; hold it where the camera sees all of it");
      }
    }
  }
  target_at_mm_ = at_mm;
  if (renderer_) renderer_->setTarget(options_.robot, options_.target, target_at_mm_);
  return simulatedRobot();
}

Result<SimulatedRobot> SyntheticSource::simulatedRobot() const {
  const synthetic::RobotCamera& c = options_.robot;
  const synthetic::CalibrationTarget& t = options_.target;
  SimulatedRobot r;
  r.target_visible = target_at_mm_.has_value();
  if (target_at_mm_) {
    r.target_x_mm = target_at_mm_->x;
    r.target_y_mm = target_at_mm_->y;
  }
  r.target_kind = synthetic::targetKindName(t.kind);
  r.target_radius_mm = t.radius_mm;
  if (t.kind == synthetic::TargetKind::kGrid) {
    r.grid_rows = t.rows;
    r.grid_cols = t.cols;
    r.grid_pitch_mm = t.pitch_mm;
  }
  r.mm_per_px = c.mm_per_px;
  r.rz_deg = c.rz_deg;
  r.dx_mm = c.dx_mm;
  r.dy_mm = c.dy_mm;
  r.tilt_x_deg = c.tilt_x_deg;
  r.tilt_y_deg = c.tilt_y_deg;
  r.robot_to_sensor =
      synthetic::RobotCameraModel(c, options_.scene.width, options_.scene.height).robotToImage();
  return r;
}

void SyntheticSource::makeRenderer(uint64_t seed_offset) {
  synthetic::SceneOptions scene = options_.scene;
  scene.seed += seed_offset;
  renderer_ = std::make_unique<synthetic::SceneRenderer>(scene);
  if (target_at_mm_) renderer_->setTarget(options_.robot, options_.target, target_at_mm_);
}

std::vector<Feature> SyntheticSource::features() { return {*feature("Parts")}; }

Result<Feature> SyntheticSource::feature(const std::string& name) {
  if (name != "Parts")
    return makeError(SourceErrc::kUnknownFeature, "unknown feature '" + name + "'");
  Feature f;
  f.name = "Parts";
  f.type = FeatureType::kInteger;
  f.value = std::to_string(options_.scene.parts);
  f.has_range = true;
  f.min = 0;
  f.max = kMaxParts;
  f.increment = 1;
  f.description = "parts in the scene (0: an empty table, e.g. to calibrate)";
  return f;
}

Result<void> SyntheticSource::setFeature(const std::string& name, const std::string& value) {
  if (name != "Parts")
    return makeError(SourceErrc::kUnknownFeature, "unknown feature '" + name + "'");
  const auto parts = parseInt(value);
  if (!parts || *parts < 0 || *parts > kMaxParts) {
    return makeError(
        SourceErrc::kBadValue,
        "Parts must be an integer in [0, " + std::to_string(kMaxParts) + "], got '" + value + "'");
  }
  const int before = options_.scene.parts;
  options_.scene.parts = static_cast<int>(*parts);
  try {
    makeRenderer(layout_);
  } catch (const std::invalid_argument& e) {
    options_.scene.parts = before;  // the old scene stays
    return makeError(SourceErrc::kBadValue, e.what());
  }
  return {};
}

cv::Mat& SyntheticSource::freeBuffer() {
  // Enough for the frames in flight in trigger mode and at moderate rates; a
  // burst beyond it gets fresh buffers.
  constexpr size_t kPoolSize = 4;
  for (auto& b : pool_) {
    // Only the pool refers to it: every frame made from it was released. The
    // count is read atomically, as other threads release their references
    // (OpenCV's own CV_XADD is C11's _Atomic under clang, which warns in C++).
    if (b.u != nullptr && __atomic_load_n(&b.u->refcount, __ATOMIC_ACQUIRE) == 1) return b;
  }
  if (pool_.size() < kPoolSize) return pool_.emplace_back();
  spare_ = cv::Mat();
  return spare_;
}

}  // namespace picksight::video
