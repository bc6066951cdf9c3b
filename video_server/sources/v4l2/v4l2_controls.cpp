// V4L2 controls as source features: enumerated, described and set by name.
#include "v4l2_source.hpp"

#include <strings.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <vector>

#include "picksight/common/log.hpp"
#include "picksight/common/text.hpp"

namespace picksight::video {
namespace {

// "Exposure Time, Absolute" -> "exposure_time_absolute", as v4l2-ctl names them.
std::string controlName(const std::string& label) {
  std::string name;
  for (char c : label) {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      name += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else if (!name.empty() && name.back() != '_') {
      name += '_';
    }
  }
  while (!name.empty() && name.back() == '_') name.pop_back();
  return name;
}

std::string range(const v4l2_queryctrl& c) {
  return "[" + std::to_string(c.minimum) + ", " + std::to_string(c.maximum) + "]";
}

// A control's names over the kernel's history, the current first: uvcvideo
// renamed several labels (Linux 5.x: "Exposure, Auto" -> "Auto Exposure"), and
// names are made from labels, so a configuration written on one kernel uses
// either. Looked up by the control's id, which never changed.
struct ControlNames {
  uint32_t id;
  std::vector<const char*> names;
};
const std::vector<ControlNames>& controlAliases() {
  static const std::vector<ControlNames> kAliases = {
      {V4L2_CID_EXPOSURE_AUTO, {"auto_exposure", "exposure_auto"}},
      {V4L2_CID_EXPOSURE_ABSOLUTE, {"exposure_time_absolute", "exposure_absolute"}},
      {V4L2_CID_EXPOSURE_AUTO_PRIORITY, {"exposure_dynamic_framerate", "exposure_auto_priority"}},
      {V4L2_CID_AUTO_WHITE_BALANCE, {"white_balance_automatic", "white_balance_temperature_auto"}},
      {V4L2_CID_FOCUS_AUTO, {"focus_automatic_continuous", "focus_auto"}},
      {V4L2_CID_AUTOGAIN, {"gain_automatic", "gain_auto"}},
  };
  return kAliases;
}

// The automatic mode that overrides a manual control, and its value for
// "manual": writing the manual control while the mode is automatic is
// refused or silently ignored by UVC cameras, so the mode is switched first.
struct AutoMode {
  uint32_t manual;
  uint32_t automatic;
  int32_t manual_value;
};
const std::vector<AutoMode>& autoModes() {
  static const std::vector<AutoMode> kModes = {
      {V4L2_CID_EXPOSURE_ABSOLUTE, V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL},
      {V4L2_CID_WHITE_BALANCE_TEMPERATURE, V4L2_CID_AUTO_WHITE_BALANCE, 0},
      {V4L2_CID_FOCUS_ABSOLUTE, V4L2_CID_FOCUS_AUTO, 0},
      {V4L2_CID_GAIN, V4L2_CID_AUTOGAIN, 0},
  };
  return kModes;
}

Error unknownFeature(const std::string& name, const std::string& card) {
  return makeError(SourceErrc::kUnknownFeature,
                   "unknown feature '" + name + "' (not a control of " + card + ")");
}

}  // namespace

std::vector<v4l2_queryctrl> V4l2Source::queryControls() {
  std::vector<v4l2_queryctrl> controls;
  auto keep = [&](const v4l2_queryctrl& q) {
    if (q.flags & V4L2_CTRL_FLAG_DISABLED) return;
    switch (q.type) {
      // Types G_CTRL/S_CTRL carry; 64-bit, string and compound controls need
      // the extended API and no webcam exposes its exposure or gain that way.
      case V4L2_CTRL_TYPE_INTEGER:
      case V4L2_CTRL_TYPE_BOOLEAN:
      case V4L2_CTRL_TYPE_MENU:
      case V4L2_CTRL_TYPE_INTEGER_MENU:
      case V4L2_CTRL_TYPE_BUTTON:
        controls.push_back(q);
        break;
      default:
        break;
    }
  };
  v4l2_queryctrl q{};
  q.id = V4L2_CTRL_FLAG_NEXT_CTRL;
  bool enumerates = false;
  while (xioctl(VIDIOC_QUERYCTRL, &q) == 0) {
    enumerates = true;
    keep(q);
    q.id |= V4L2_CTRL_FLAG_NEXT_CTRL;
  }
  if (!enumerates) {
    // Drivers older than the NEXT_CTRL flag: ask for the user-class ids one by one.
    for (uint32_t id = V4L2_CID_BASE; id < V4L2_CID_LASTP1; ++id) {
      v4l2_queryctrl one{};
      one.id = id;
      if (xioctl(VIDIOC_QUERYCTRL, &one) == 0) keep(one);
    }
  }
  return controls;
}

std::optional<v4l2_queryctrl> V4l2Source::findControl(const std::string& name) {
  const std::vector<v4l2_queryctrl> controls = queryControls();
  for (const auto& q : controls) {
    if (controlName(kernelString(q.name)) == name) return q;
  }
  // Another kernel's name for the same control.
  for (const ControlNames& alias : controlAliases()) {
    if (std::find(alias.names.begin(), alias.names.end(), name) == alias.names.end()) continue;
    for (const auto& q : controls) {
      if (q.id == alias.id) return q;
    }
  }
  return std::nullopt;
}

std::optional<std::string> V4l2Source::leaveAutoMode(const v4l2_queryctrl& manual) {
  for (const AutoMode& mode : autoModes()) {
    if (mode.manual != manual.id) continue;
    v4l2_control c{};
    c.id = mode.automatic;
    // No such control, or already manual: nothing to do.
    if (xioctl(VIDIOC_G_CTRL, &c) < 0 || c.value == mode.manual_value) return std::nullopt;
    v4l2_queryctrl q{};
    q.id = mode.automatic;
    const std::string automatic =
        xioctl(VIDIOC_QUERYCTRL, &q) == 0 ? controlName(kernelString(q.name)) : "its auto mode";
    c.value = mode.manual_value;
    if (xioctl(VIDIOC_S_CTRL, &c) < 0) return std::nullopt;  // the write below then says why
    switched_to_manual_.insert(manual.id);
    return automatic;
  }
  return std::nullopt;
}

std::vector<std::pair<int32_t, std::string>> V4l2Source::menuChoices(const v4l2_queryctrl& q) {
  std::vector<std::pair<int32_t, std::string>> menu;
  for (int32_t i = q.minimum; i <= q.maximum; ++i) {
    v4l2_querymenu m{};
    m.id = q.id;
    m.index = static_cast<uint32_t>(i);
    if (xioctl(VIDIOC_QUERYMENU, &m) < 0) continue;  // a hole in the menu
    menu.emplace_back(
        i, q.type == V4L2_CTRL_TYPE_MENU ? kernelString(m.name) : std::to_string(m.value));
  }
  return menu;
}

Result<Feature> V4l2Source::describeControl(const v4l2_queryctrl& q) {
  Feature f;
  f.name = controlName(kernelString(q.name));
  f.description = kernelString(q.name);
  if (q.flags & V4L2_CTRL_FLAG_INACTIVE) f.description += " (inactive: set by an automatic mode)";
  if (switched_to_manual_.count(q.id) > 0) {
    f.description += " (its automatic mode was switched to manual when a value was written)";
  }
  f.writable = !(q.flags & V4L2_CTRL_FLAG_READ_ONLY);
  if (q.id == V4L2_CID_EXPOSURE_ABSOLUTE) f.unit = "100us";

  int32_t value = 0;
  if (q.type != V4L2_CTRL_TYPE_BUTTON && !(q.flags & V4L2_CTRL_FLAG_WRITE_ONLY)) {
    v4l2_control c{};
    c.id = q.id;
    if (xioctl(VIDIOC_G_CTRL, &c) < 0) return deviceError("VIDIOC_G_CTRL " + f.name);
    value = c.value;
  }
  switch (q.type) {
    case V4L2_CTRL_TYPE_INTEGER:
      f.type = FeatureType::kInteger;
      f.value = std::to_string(value);
      f.has_range = true;
      f.min = q.minimum;
      f.max = q.maximum;
      f.increment = q.step > 1 ? q.step : 0;
      break;
    case V4L2_CTRL_TYPE_BOOLEAN:
      f.type = FeatureType::kBoolean;
      f.value = value ? "true" : "false";
      break;
    case V4L2_CTRL_TYPE_BUTTON:
      f.type = FeatureType::kCommand;
      break;
    default: {  // menus: choices by name (integer menus by value), gaps skipped
      f.type = FeatureType::kEnumeration;
      for (const auto& [index, choice] : menuChoices(q)) {
        f.choices.push_back(choice);
        if (index == value) f.value = choice;
      }
      break;
    }
  }
  return f;
}

std::vector<Feature> V4l2Source::features() {
  std::vector<Feature> out;
  if (!fd_) return out;
  for (const auto& q : queryControls()) {
    if (auto f = describeControl(q)) out.push_back(std::move(*f));
  }
  return out;
}

Result<Feature> V4l2Source::feature(const std::string& name) {
  if (!fd_) return notOpen();
  const auto q = findControl(name);
  if (!q) return unknownFeature(name, card_);
  return describeControl(*q);
}

Result<void> V4l2Source::setFeature(const std::string& name, const std::string& text) {
  if (!fd_) return notOpen();
  const auto found = findControl(name);
  if (!found) return unknownFeature(name, card_);
  const v4l2_queryctrl& q = *found;
  if (q.flags & V4L2_CTRL_FLAG_READ_ONLY)
    return makeError(SourceErrc::kBadValue, "feature '" + name + "' is read-only");

  long long value = 0;
  switch (q.type) {
    case V4L2_CTRL_TYPE_BUTTON:
      value = 1;  // pressing it; the text does not matter
      break;
    case V4L2_CTRL_TYPE_BOOLEAN:
      if (text == "true" || text == "1" || text == "on") {
        value = 1;
      } else if (text == "false" || text == "0" || text == "off") {
        value = 0;
      } else {
        return makeError(SourceErrc::kBadValue,
                         "feature '" + name + "' is a boolean (true/false), got '" + text + "'");
      }
      break;
    case V4L2_CTRL_TYPE_INTEGER:
      if (const auto parsed = parseInt(text)) {
        value = *parsed;
      } else {
        return makeError(SourceErrc::kBadValue, "feature '" + name + "' is an integer " + range(q) +
                                                    ", got '" + text + "'");
      }
      if (value < q.minimum || value > q.maximum) {
        return makeError(SourceErrc::kBadValue,
                         "feature '" + name + "' value " + text + " out of range " + range(q));
      }
      if (q.step > 1 && (value - q.minimum) % q.step != 0) {
        return makeError(SourceErrc::kBadValue, "feature '" + name + "' value " + text +
                                                    " is not " + std::to_string(q.minimum) +
                                                    " plus a multiple of " +
                                                    std::to_string(q.step) + " in " + range(q));
      }
      break;
    default: {  // menus: a choice by its name, or by its index
      const auto menu = menuChoices(q);
      bool matched = false;
      for (const auto& [index, choice] : menu) {
        if (!matched &&
            (strcasecmp(choice.c_str(), text.c_str()) == 0 || text == std::to_string(index))) {
          value = index;
          matched = true;
        }
      }
      if (!matched) {
        std::string choices;
        for (const auto& c : menu) choices += (choices.empty() ? "" : ", ") + c.second;
        return makeError(SourceErrc::kBadValue, "feature '" + name + "' has no choice '" + text +
                                                    "' (choices: " + choices + ")");
      }
      break;
    }
  }
  // A manual value under an automatic mode would be refused or ignored.
  if (const auto automatic = leaveAutoMode(q)) {
    logInfo("v4l2:", options_.path, ": ", *automatic, " switched to manual so that ", name, " = ",
            text, " applies");
  }
  v4l2_control c{};
  c.id = q.id;
  c.value = static_cast<int32_t>(value);
  if (xioctl(VIDIOC_S_CTRL, &c) < 0) {
    const int err = errno;
    if (err == ERANGE || err == EINVAL) {
      return makeError(SourceErrc::kBadValue,
                       "feature '" + name + "' refused " + text + " (range " + range(q) + ")");
    }
    if (err == EACCES || err == EBUSY) {
      return makeError(SourceErrc::kBadValue,
                       "feature '" + name + "' cannot be set now: " + std::strerror(err) +
                           " (inactive under an automatic mode, e.g. exposure needs "
                           "auto_exposure on manual)");
    }
    errno = err;
    return deviceError("VIDIOC_S_CTRL " + name);
  }
  return {};
}

}  // namespace picksight::video
