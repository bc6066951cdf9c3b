// Run-time vision settings: keys, bounds, text, file, stale models.
#include "picksight/cell/vision_settings.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>
#include <sstream>

#include "picksight/common/text.hpp"

namespace picksight::cell {

using store::ModelList;

const char* errorName(VisionSettingsErrc e) {
  switch (e) {
    case VisionSettingsErrc::kBadSetting:
      return "bad setting";
    case VisionSettingsErrc::kDamaged:
      return "damaged";
    case VisionSettingsErrc::kStorage:
      return "storage";
  }
  return "unknown";
}

namespace {

constexpr const char* kFormat = "picksight-vision-settings";
constexpr int kVersion = 1;
// Bounds as the command line's (app_options.cpp): past them a value is a typo.
constexpr int kMinWindow = 8;
constexpr int kMaxWindow = 16384;
constexpr double kMaxArea = 1e9;

// Up to 40 characters of a person's text, safe to echo in a reply line.
std::string printableText(std::string_view text) {
  constexpr size_t kLimit = 40;
  std::string out;
  for (char c : text.substr(0, kLimit)) {
    const auto u = static_cast<unsigned char>(c);
    out += u >= 0x20 && u < 0x7f ? c : '?';
  }
  if (text.size() > kLimit) out += "...";
  return out;
}

std::string lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

const char* methodName(vision::ThresholdMethod m) {
  switch (m) {
    case vision::ThresholdMethod::kOtsu:
      return "otsu";
    case vision::ThresholdMethod::kFixed:
      return "fixed";
    case vision::ThresholdMethod::kAdaptive:
      break;
  }
  return "adaptive";
}

// One key: what it accepts (for errors) and how a value applies; nullopt
// from `set` means the value is out of bounds.
struct SettingKey {
  const char* name;
  const char* accepts;
  bool (*set)(VisionOptions&, const std::string&);
};

std::optional<double> areaValue(const std::string& v, double low) {
  const auto n = parseDouble(v);
  if (!n || !std::isfinite(*n) || *n < low || *n > kMaxArea) return std::nullopt;
  return n;
}

const SettingKey kKeys[] = {
    {"polarity", "dark (dark parts on a light surface) or light (light parts on a dark one)",
     [](VisionOptions& o, const std::string& v) {
       const std::string l = lower(v);
       if (l != "dark" && l != "light") return false;
       o.binarize.polarity =
           l == "dark" ? vision::Polarity::kDarkOnLight : vision::Polarity::kLightOnDark;
       return true;
     }},
    {"threshold", "adaptive, otsu or fixed (at level)",
     [](VisionOptions& o, const std::string& v) {
       const std::string l = lower(v);
       if (l == "adaptive") {
         o.binarize.method = vision::ThresholdMethod::kAdaptive;
       } else if (l == "otsu") {
         o.binarize.method = vision::ThresholdMethod::kOtsu;
       } else if (l == "fixed") {
         o.binarize.method = vision::ThresholdMethod::kFixed;
       } else {
         return false;
       }
       return true;
     }},
    {"level", "an integer grey level in [0, 255] (threshold fixed)",
     [](VisionOptions& o, const std::string& v) {
       const auto n = parseInt(v);
       if (!n || *n < 0 || *n > 255) return false;
       o.binarize.fixed_threshold = static_cast<int>(*n);
       return true;
     }},
    {"window", "0 (a sixth of the smaller image side) or an integer in [8, 16384] pixels",
     [](VisionOptions& o, const std::string& v) {
       const auto n = parseInt(v);
       if (!n || (*n != 0 && (*n < kMinWindow || *n > kMaxWindow))) return false;
       o.binarize.adaptive_window = static_cast<int>(*n);
       return true;
     }},
    {"min_area",
     "auto (50 px, or a twentieth of the smallest trained part when that is more) or a number "
     "in [1, 1e9] sensor pixels",
     [](VisionOptions& o, const std::string& v) {
       if (lower(v) == "auto") {
         o.regions.min_area = vision::RegionOptions{}.min_area;
         o.min_area_follows_models = true;
         return true;
       }
       const auto n = areaValue(v, 1);
       if (!n) return false;
       o.regions.min_area = *n;
       o.min_area_follows_models = false;
       return true;
     }},
    {"min_hole_area", "a number in [0, 1e9] sensor pixels",
     [](VisionOptions& o, const std::string& v) {
       const auto n = areaValue(v, 0);
       if (!n) return false;
       o.regions.min_hole_area = *n;
       return true;
     }},
};

const SettingKey* findKey(std::string_view name) {
  for (const auto& key : kKeys) {
    if (lower(name) == key.name) return &key;
  }
  return nullptr;
}

std::string keyNames() {
  std::string names;
  for (const auto& key : kKeys) names += (names.empty() ? "" : ", ") + std::string(key.name);
  return names;
}

// Full precision: a value read back from the file is the one written.
std::string numberText(double v) {
  std::ostringstream out;
  out.precision(17);
  out << v;
  return out.str();
}

std::string modelName(const vision::PartModel& m) {
  return std::to_string(m.type) + " (" + m.name + ")";
}

}  // namespace

const std::vector<std::string>& visionSettingKeys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> out;
    for (const auto& key : kKeys) out.emplace_back(key.name);
    return out;
  }();
  return keys;
}

std::string visionSettingsText(const VisionOptions& o) {
  return std::string("polarity=") +
         (o.binarize.polarity == vision::Polarity::kDarkOnLight ? "dark" : "light") +
         " threshold=" + methodName(o.binarize.method) +
         " level=" + std::to_string(o.binarize.fixed_threshold) +
         " window=" + std::to_string(o.binarize.adaptive_window) +
         " min_area=" + (o.min_area_follows_models ? "auto" : formatFixed(o.regions.min_area)) +
         " min_hole_area=" + formatFixed(o.regions.min_hole_area);
}

Result<VisionOptions> applyVisionSettings(
    VisionOptions options, const std::vector<std::pair<std::string, std::string>>& pairs) {
  std::set<std::string> seen;
  for (const auto& [name, value] : pairs) {
    const SettingKey* key = findKey(name);
    if (!key) {
      return makeError(VisionSettingsErrc::kBadSetting,
                       "no key '" + printableText(name) + "' (keys: " + keyNames() + ")");
    }
    if (!seen.insert(key->name).second)
      return makeError(VisionSettingsErrc::kBadSetting, std::string(key->name) + " given twice");
    if (!key->set(options, value)) {
      return makeError(VisionSettingsErrc::kBadSetting, std::string(key->name) + " must be " +
                                                            key->accepts + ", got '" +
                                                            printableText(value) + "'");
    }
  }
  return options;
}

std::string visionSettingsJson(const VisionOptions& o) {
  nlohmann::ordered_json j;
  j["format"] = kFormat;
  j["version"] = kVersion;
  j["polarity"] = o.binarize.polarity == vision::Polarity::kDarkOnLight ? "dark" : "light";
  j["threshold"] = methodName(o.binarize.method);
  j["level"] = o.binarize.fixed_threshold;
  j["window"] = o.binarize.adaptive_window;
  if (o.min_area_follows_models) {
    j["min_area"] = "auto";
  } else {
    j["min_area"] = o.regions.min_area;
  }
  j["min_hole_area"] = o.regions.min_hole_area;
  return j.dump(2) + "\n";
}

Result<VisionOptions> parseVisionSettingsJson(const std::string& text, VisionOptions base,
                                              const std::vector<std::string>& keep) {
  const auto damaged = [](const std::string& why) {
    return makeError(VisionSettingsErrc::kDamaged, why);
  };
  // The file holds six keys: anything this large was not written by VISION.
  constexpr size_t kMaxFileBytes = 64 * 1024;
  if (text.size() > kMaxFileBytes) return damaged("larger than 64 KiB");
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded()) return damaged("not JSON");
  if (!j.is_object()) return damaged("not a JSON object");
  if (!j.contains("format") || j["format"] != kFormat)
    return damaged(std::string("format is not '") + kFormat + "'");
  if (!j.contains("version") || !j["version"].is_number_integer() || j["version"] != kVersion)
    return damaged("version is not " + std::to_string(kVersion));
  std::vector<std::pair<std::string, std::string>> pairs;
  std::vector<std::pair<std::string, std::string>> used;  // those `keep` leaves
  for (const auto& [name, value] : j.items()) {
    if (name == "format" || name == "version") continue;
    if (!findKey(name)) return damaged("no key '" + printableText(name) + "'");
    if (value.is_string()) {
      pairs.emplace_back(name, value.get<std::string>());
    } else if (value.is_number_integer()) {
      pairs.emplace_back(name, std::to_string(value.get<long long>()));
    } else if (value.is_number_float()) {
      pairs.emplace_back(name, numberText(value.get<double>()));
    } else {
      return damaged(name + " is neither a string nor a number");
    }
    if (std::find(keep.begin(), keep.end(), name) == keep.end()) used.push_back(pairs.back());
  }
  // Every value checked, those the command line overrides too: a file
  // that is wrong is wrong whatever overrides it today.
  if (auto all = applyVisionSettings(base, pairs); !all) return damaged(all.error().message);
  auto applied = applyVisionSettings(std::move(base), used);
  if (!applied) return damaged(applied.error().message);
  return applied;
}

std::vector<std::string> modelsToReteach(const VisionOptions& before, const VisionOptions& after,
                                         const ModelList& models) {
  std::vector<std::string> out;
  const bool polarity = before.binarize.polarity != after.binarize.polarity;
  for (const auto& m : models) {
    std::vector<std::string> why;
    if (polarity && !m.taught_polarity) {
      why.push_back(
          "taught before its polarity was recorded (re-teach it if LOCATE no longer "
          "finds it)");
    } else if (m.taught_polarity && *m.taught_polarity != after.binarize.polarity) {
      why.push_back(std::string("taught as ") +
                    (*m.taught_polarity == vision::Polarity::kDarkOnLight ? "dark" : "light") +
                    " on its surface");
    }
    // Only a change of the setting concerns a model: one taught under other
    // settings (before a restart) was named when they changed.
    if (before.regions.min_hole_area != after.regions.min_hole_area &&
        m.min_hole_area != after.regions.min_hole_area) {
      why.push_back("counts holes from " + formatFixed(m.min_hole_area) + " px");
    }
    const double min_area = after.min_area_follows_models ? 0 : after.regions.min_area;
    if ((before.regions.min_area != after.regions.min_area ||
         before.min_area_follows_models != after.min_area_follows_models) &&
        m.min_region_area > 0 && m.min_region_area < min_area) {
      why.push_back("keeps regions from " + formatFixed(m.min_region_area) + " px");
    }
    if (why.empty()) continue;
    std::string line = modelName(m) + " ";
    for (size_t i = 0; i < why.size(); ++i) line += (i == 0 ? "" : ", ") + why[i];
    out.push_back(line);
  }
  return out;
}

}  // namespace picksight::cell
