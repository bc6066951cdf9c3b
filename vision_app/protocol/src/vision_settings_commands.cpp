// VISION: read, change or reset the vision settings while the cell runs.
#include "picksight/protocol/vision_settings_commands.hpp"

#include <utility>
#include <vector>

#include "picksight/cell/vision_settings.hpp"
#include "picksight/common/text.hpp"

namespace picksight::app {
namespace {

constexpr const char* kUsage = "VISION [RESET | <key> <value> [<key> <value>]...]";

std::string settingsReply(const VisionService& vision) {
  std::string reply = "OK " + visionSettingsText(vision.options());
  if (auto damage = vision.settingsDamage()) {
    reply += " ; error: the settings file is damaged (" + damage->substr(0, 200) +
             "), LOCATE and LEARN refused: repair it and restart, or VISION RESET";
  }
  return reply;
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
  return reply;
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

}  // namespace picksight::app
