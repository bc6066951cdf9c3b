// A YAML file of command-line options (--config FILE): each key is an
// option's long name without dashes, a list repeats the option, a flag is
// true or false; the command line overrides the file. One implementation for
// every tool that takes --config, so the file's syntax and its error
// messages are the same everywhere.
#pragma once

#include <functional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "picksight/cli/command_line.hpp"

namespace picksight::cli {

// What one parse of argument words found besides the options themselves.
struct ConfigParseExtras {
  std::string config_file;      // the --config value, empty without it
  std::set<std::string> given;  // long names (without dashes) on the line
};

// The YAML map of `path` as argument words ("--key=value") for the options
// of `app`, leaving out the keys in `skip`. Keys are checked against the
// options themselves, so an option added to a tool is a config key with no
// further code. Errors name the file and the key.
Result<std::vector<std::string>> configFileWords(const std::string& path, const App& app,
                                                 const std::set<std::string>& skip);

// Parses `args` with `parse` (words, help, extras -> Result<T>; extras may be
// null), and when they name a --config file, parses the file's words first
// and the command line over them. `app` declares the tool's options (for the
// file's keys). A bad value in the file is reported as the file's key.
template <typename T>
Result<T> parseWithConfigFile(const std::vector<std::string>& args, bool* help, const App& app,
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
std::string toolUsage(App (*make)(), void (*define)(App&, Options&, Raw&)) {
  App app = make();
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
Result<Options> parseToolOptions(const std::vector<std::string>& args, bool* help, App (*make)(),
                                 void (*define)(App&, Options&, Raw&),
                                 Result<Options> (*finish)(Options, Raw&)) {
  const auto parseWords = [&](const std::vector<std::string>& words, bool* asked_help,
                              ConfigParseExtras* extras) -> Result<Options> {
    App app = make();
    Options options;
    Raw raw;
    define(app, options, raw);
    if (auto ok = parseArgs(app, words, asked_help); !ok) return ok.error();
    if (extras) {
      extras->config_file = raw.config_file;
      extras->given = app.givenOptions();
    }
    return finish(std::move(options), raw);
  };
  App app = make();
  Options unused;
  Raw raw;
  define(app, unused, raw);
  return parseWithConfigFile<Options>(args, help, app, parseWords);
}

}  // namespace picksight::cli
