// The vision settings a person changes while the cell runs (the robot
// protocol's VISION, the HMI's Vision panel): their keys and bounds, their
// one-line text, their file (<data dir>/vision.json), and which trained
// models a change leaves taught under other settings.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "picksight/cell/vision_service.hpp"
#include "picksight/common/result.hpp"
#include "picksight/vision/models/part_model.hpp"

namespace picksight::cell {

enum class VisionSettingsErrc {
  kBadSetting = 1,  // an unknown key, a key twice, a value out of bounds
  kDamaged,         // the settings file exists but cannot be used
  kStorage,         // the settings file could not be written
};
const char* errorName(VisionSettingsErrc e);
PICKSIGHT_ERROR_DOMAIN(VisionSettingsErrc, "vision settings")

// The keys, in the order VISION prints them: polarity, threshold, level,
// window, min_area, min_hole_area.
const std::vector<std::string>& visionSettingKeys();

// "polarity=dark threshold=adaptive level=128 window=0 min_area=auto
// min_hole_area=0.000": every key with its value, as VISION replies.
std::string visionSettingsText(const VisionOptions& options);

// `options` with the (key, value) pairs applied, keys in any case. Every
// pair is checked before any applies: an unknown key, a key given twice or
// a value out of its bounds is kBadSetting naming the key and what it
// accepts.
Result<VisionOptions> applyVisionSettings(
    VisionOptions options, const std::vector<std::pair<std::string, std::string>>& pairs);

// The settings file's text (JSON, with a format name and version) and its
// reading: `base` with the file's values, except `keep` (keys set on the
// command line, which win). Anything wrong (not JSON, another format, an
// unknown key, a value out of bounds) is kDamaged naming the key.
std::string visionSettingsJson(const VisionOptions& options);
Result<VisionOptions> parseVisionSettingsJson(const std::string& text, VisionOptions base,
                                              const std::vector<std::string>& keep = {});

// The models a change from `before` to `after` leaves taught under other
// settings, as "<type> (<name>)" with why, for the reply: a polarity change
// makes every model one of the other polarity's regions; a model counts
// holes with the minimum hole area it was taught with, and lowers the
// smallest region to its own. Threshold and window changes leave models
// alone: they match the parts' outlines, which the area tolerance and the
// boundary check follow. Empty: nothing needs a re-teach.
std::vector<std::string> modelsToReteach(const VisionOptions& before, const VisionOptions& after,
                                         const store::ModelList& models);

}  // namespace picksight::cell

PICKSIGHT_ERROR_ENUM(picksight::cell::VisionSettingsErrc)
