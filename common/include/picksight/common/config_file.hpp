// A YAML file of command-line options (--config FILE): each key is an
// option's long name without dashes, a list repeats the option, a flag is
// true or false; the command line overrides the file. One implementation for
// every tool that takes --config, so the file's syntax and its error
// messages are the same everywhere.
// Header-only: include it only from targets that link CLI11 and yaml-cpp.
#pragma once

#include <yaml-cpp/yaml.h>

#include <CLI/CLI.hpp>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "picksight/common/command_line.hpp"

namespace picksight {

// What one parse of argument words found besides the options themselves.
struct ConfigParseExtras {
  std::string config_file;      // the --config value, empty without it
  std::set<std::string> given;  // long names (without dashes) on the line
};

// The long names of the options `app` was given in its last parse.
inline std::set<std::string> givenOptions(const CLI::App& app) {
  std::set<std::string> given;
  for (const CLI::Option* opt : app.get_options()) {
    if (opt->count() > 0)
      for (const auto& name : opt->get_lnames()) given.insert(name);
  }
  return given;
}

// The YAML map of `path` as argument words ("--key=value") for the options
// of `app`, leaving out the keys in `skip`. Keys are checked against the
// options themselves, so an option added to a tool is a config key with no
// further code. Errors name the file and the key.
inline Result<std::vector<std::string>> configFileWords(const std::string& path,
                                                        const CLI::App& app,
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
    const CLI::Option* opt = key == "config" || key == "help" || key.rfind('-', 0) == 0
                                 ? nullptr
                                 : app.get_option_no_throw("--" + key);
    if (!opt) return keyError(key, "unknown key (keys are the options without dashes)");
    if (!seen.insert(key).second) return keyError(key, "given twice");
    if (skip.count(key)) continue;  // the command line wins
    const YAML::Node& value = kv.second;
    if (opt->get_type_size() == 0) {  // a flag: true or false
      bool on = false;
      if (!value.IsScalar() || !YAML::convert<bool>::decode(value, on)) {
        return keyError(key, "must be true or false");
      }
      if (on) words.push_back("--" + key);
    } else if (value.IsScalar()) {
      words.push_back("--" + key + "=" + value.Scalar());
    } else if (value.IsSequence() && opt->get_items_expected_max() > 1) {
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

// Parses `args` with `parse` (words, help, extras -> Result<T>; extras may be
// null), and when they name a --config file, parses the file's words first
// and the command line over them. `app` declares the tool's options (for the
// file's keys). A bad value in the file is reported as the file's key.
template <typename T>
Result<T> parseWithConfigFile(const std::vector<std::string>& args, bool* help, const CLI::App& app,
                              const std::function<Result<T>(const std::vector<std::string>&, bool*,
                                                            ConfigParseExtras*)>& parse) {
  ConfigParseExtras line;
  auto options = parse(args, help, &line);
  if (!options || (help && *help) || line.config_file.empty()) return options;
  auto words = configFileWords(line.config_file, app, line.given);
  if (!words) return words.error();
  // The file alone first, so that a bad value is reported as its key.
  if (auto from_file = parse(*words, nullptr, nullptr); !from_file) {
    std::string message = from_file.error().message;
    if (message.rfind("--", 0) == 0) message.erase(0, 2);
    return makeError(CommandLineErrc::kBadOption, line.config_file + ": " + message);
  }
  words->insert(words->end(), args.begin(), args.end());
  return parse(*words, nullptr, nullptr);
}

// A tool's --help text (`make` and `define` as for parseToolOptions).
template <typename Options, typename Raw>
std::string toolUsage(CLI::App (*make)(), void (*define)(CLI::App&, Options&, Raw&)) {
  CLI::App app = make();
  Options unused;
  Raw raw;
  define(app, unused, raw);
  return app.help();
}

// A tool's whole option parse, --config included: `make` builds the app,
// `define` declares every option into the tool's options and the raw
// strings its validators check (Raw has a config_file member for
// --config), and `finish` turns the raw strings into the options once the
// validators passed them. The command line parsed once per source of words
// (the file, then the file and the line), each time into fresh options.
template <typename Options, typename Raw>
Result<Options> parseToolOptions(const std::vector<std::string>& args, bool* help,
                                 CLI::App (*make)(), void (*define)(CLI::App&, Options&, Raw&),
                                 Result<Options> (*finish)(Options, Raw&)) {
  const auto parseWords = [&](const std::vector<std::string>& words, bool* asked_help,
                              ConfigParseExtras* extras) -> Result<Options> {
    CLI::App app = make();
    Options options;
    Raw raw;
    define(app, options, raw);
    if (auto ok = parseArgs(app, words, asked_help); !ok) return ok.error();
    if (extras) {
      extras->config_file = raw.config_file;
      extras->given = givenOptions(app);
    }
    return finish(std::move(options), raw);
  };
  CLI::App app = make();
  Options unused;
  Raw raw;
  define(app, unused, raw);
  return parseWithConfigFile<Options>(args, help, app, parseWords);
}

}  // namespace picksight
