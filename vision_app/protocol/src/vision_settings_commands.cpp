// VISION: read, change or reset the vision settings while the cell runs.
#include "picksight/protocol/vision_settings_commands.hpp"

#include <cmath>
#include <utility>
#include <vector>

#include "picksight/cell/vision_settings.hpp"
#include "picksight/common/text.hpp"

namespace picksight::protocol {

using cell::modelsToReteach;
using cell::VisionService;
using cell::visionSettingsText;

namespace {

constexpr const char* kUsage = "VISION [RESET | <key> <value> [<key> <value>]...]";

// Over this share of the frame taken for part, the surface most likely is:
// parts lie apart on a surface larger than they are.
constexpr double kSurfaceShare = 0.5;

// " ; hint: ..." when the settings in force take most of the last frame for
// part, naming the other polarity; empty otherwise.
std::string polarityHint(const VisionService& vision) {
  const auto share = vision.partShareOfLastFrame();
  if (!share || *share <= kSurfaceShare) return "";
  const bool dark = vision.options().binarize.polarity == vision::Polarity::kDarkOnLight;
  return " ; hint: " + std::to_string(std::lround(100 * *share)) +
         " % of the last frame is taken for part, more than the surface: parts " +
         (dark ? "lighter" : "darker") + " than their surface need VISION polarity " +
         (dark ? "light" : "dark");
}

std::string settingsReply(const VisionService& vision) {
  std::string reply = "OK " + visionSettingsText(vision.options());
  if (auto damage = vision.settingsDamage()) {
    reply += " ; error: the settings file is damaged (" + damage->substr(0, 200) +
             "), LOCATE and LEARN refused: repair it and restart, or VISION RESET";
  }
  return reply + polarityHint(vision);
}

std::string change(VisionService& vision, const Request& r) {
  if (r.args.size() % 2 != 0)
    return errorReply(ProtocolErrc::kBadArguments, std::string("usage: ") + kUsage);
  std::vector<std::pair<std::string, std::string>> pairs;
  for (size_t i = 0; i + 1 < r.args.size(); i += 2) pairs.emplace_back(r.args[i], r.args[i + 1]);
  auto changed = vision.changeSettings(pairs);
  if (!changed) return errorReply(changed.error());
  const auto& [before, after] = *changed;
  std::string reply = "OK " + visionSettingsText(after);
  // Robots read the fields up to the first ';'.
  const auto models = vision.models() ? vision.models()->snapshot() : nullptr;
  if (models) {
    for (const auto& stale : modelsToReteach(before, after, *models))
      reply += " ; re-teach: " + stale;
  }
  return reply + polarityHint(vision);
}

}  // namespace

void addVisionSettingsCommands(CommandTable& table, VisionService& vision) {
  table.add(
      "VISION", kUsage,
      [&vision](const Request& r) {
        if (r.args.empty()) return settingsReply(vision);
        if (r.args.size() == 1 && toUpper(r.args[0]) == "RESET") {
          auto reset = vision.resetSettings();
          if (!reset) return errorReply(reset.error());
          return "OK " + visionSettingsText(*reset);
        }
        return change(vision, r);
      },
      changesWithArguments);
}

}  // namespace picksight::protocol
