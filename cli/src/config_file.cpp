// --config FILE: a YAML map of options read as command-line words.

#include "picksight/cli/config_file.hpp"

#include <yaml-cpp/yaml.h>

namespace picksight::cli {

Result<std::vector<std::string>> configFileWords(const std::string& path, const App& app,
                                                 const std::set<std::string>& skip) {
  const auto keyError = [&](const std::string& key, const std::string& message) {
    return makeError(CommandLineErrc::kBadOption, path + ": " + key + ": " + message);
  };
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    return makeError(CommandLineErrc::kBadOption, "--config " + path + ": " + e.what());
  }
  if (root.IsNull()) return std::vector<std::string>();  // an empty file
  if (!root.IsMap()) {
    return makeError(CommandLineErrc::kBadOption,
                     path + ": must be a map of option names to values");
  }
  std::vector<std::string> words;
  std::set<std::string> seen;
  for (const auto& kv : root) {
    if (!kv.first.IsScalar()) {
      return makeError(CommandLineErrc::kBadOption, path + ": keys must be plain option names");
    }
    const std::string key = kv.first.Scalar();
    const std::optional<App::Shape> shape =
        key == "config" || key == "help" || key.rfind('-', 0) == 0 ? std::nullopt
                                                                   : app.shapeOf("--" + key);
    if (!shape) return keyError(key, "unknown key (keys are the options without dashes)");
    if (!seen.insert(key).second) return keyError(key, "given twice");
    if (skip.count(key)) continue;  // the command line wins
    const YAML::Node& value = kv.second;
    if (shape->flag) {  // true or false
      bool on = false;
      if (!value.IsScalar() || !YAML::convert<bool>::decode(value, on)) {
        return keyError(key, "must be true or false");
      }
      if (on) words.push_back("--" + key);
    } else if (value.IsScalar()) {
      words.push_back("--" + key + "=" + value.Scalar());
    } else if (value.IsSequence() && shape->list) {
      for (const auto& item : value) {
        if (!item.IsScalar()) return keyError(key, "must be a list of values");
        words.push_back("--" + key + "=" + item.Scalar());
      }
    } else {
      return keyError(key, value.IsSequence() ? "takes one value, not a list" : "must be a value");
    }
  }
  return words;
}

}  // namespace picksight::cli
