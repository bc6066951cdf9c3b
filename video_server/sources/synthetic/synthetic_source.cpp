// Synthetic camera source over the scene generator.
#include "synthetic_source.hpp"

#include <algorithm>

#include "picksight/common/clock.hpp"
#include "picksight/common/text.hpp"

namespace picksight::video {

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
      if (!integer || *integer < 0 || *integer > 500) return bad("an integer in [0, 500]");
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
      if (value != "uneven" && value != "flat") return bad("uneven or flat");
      o.scene.uneven_light = value == "uneven";
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
    } else if (key == "scene_every") {
      if (!integer || *integer < 0) return bad("a non-negative integer");
      o.scene_every = static_cast<uint64_t>(*integer);
    } else {
      return makeError(SourceErrc::kBadConfig,
                       "synthetic: unknown key '" + key +
                           "' (known: width, height, parts, seed, noise, size, light, types, "
                           "touching, blur, scene_every)");
    }
  }
  return o;
}

SyntheticSource::SyntheticSource(SyntheticSourceOptions options) : options_(std::move(options)) {}

Result<void> SyntheticSource::open() {
  if (!renderer_) renderer_ = std::make_unique<synthetic::SceneRenderer>(options_.scene);
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
      synthetic::SceneOptions scene = options_.scene;
      scene.seed += layout;
      renderer_ = std::make_unique<synthetic::SceneRenderer>(scene);
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
  return frame;
}

cv::Mat& SyntheticSource::freeBuffer() {
  // Enough for the frames in flight in trigger mode and at moderate rates; a
  // burst beyond it gets fresh buffers.
  constexpr size_t kPoolSize = 4;
  for (auto& b : pool_) {
    // Only the pool refers to it: every frame made from it was released. The
    // count is read atomically, as other threads release their references.
    if (b.u != nullptr && CV_XADD(&b.u->refcount, 0) == 1) return b;
  }
  if (pool_.size() < kPoolSize) return pool_.emplace_back();
  spare_ = cv::Mat();
  return spare_;
}

}  // namespace picksight::video
