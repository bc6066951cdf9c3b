// picksight-cam's command line: CLI11 does the parsing; this file declares the
// commands and turns CLI11's errors into messages that name the command.
#include "cam_command_line.hpp"

#include <algorithm>
#include <cctype>
#include <limits>
#include <memory>
#include <optional>
#include <utility>

#include <CLI/CLI.hpp>

#include "cam_cli.hpp"
#include "picksight/common/text.hpp"

namespace picksight::cam {

namespace {

// One line of the command list in the help: a synopsis and what it does.
struct UsageLine {
  const char* synopsis;
  const char* help;  // may hold '\n' for a continuation line
};

// A subcommand: its positional arguments in order, and its help lines. A
// command with two forms (size) lists both.
struct CommandSpec {
  const char* name;
  std::vector<const char*> required;
  std::vector<const char*> optional;
  std::vector<UsageLine> usage;
};

const std::vector<CommandSpec>& commandSpecs() {
  static const std::vector<CommandSpec> kSpecs = {
      {"list", {}, {}, {{"list", "cameras, their sources, states and modes"}}},
      {"info", {"CAM"}, {}, {{"info CAM", "vendor, model, sensor, ROI, output size, format"}}},
      {"roi",
       {"CAM", "X", "Y", "W", "H"},
       {},
       {{"roi CAM X Y W H", "crop to a sensor region (W H 0 0 = full sensor)"}}},
      // W and H are optional to CLI11 because --scale replaces them; parse()
      // checks that one of the two forms is complete.
      {"size",
       {"CAM"},
       {"W", "H"},
       {{"size CAM W H", "resize the ROI to W x H pixels (0 0 = ROI size)"},
        {"size CAM --scale S", "resize the ROI by the factor S"}}},
      {"mode",
       {"CAM", "MODE"},
       {"FPS"},
       {{"mode CAM freerun|trigger [FPS]", "acquisition mode, and frame rate"},
        {"mode CAM hardware [--line L] [--activation EDGE] [--trigger-timeout MS]",
         "\none frame per pulse on the camera's input L (default Line1);\nEDGE rising, falling, "
         "any, high or low; a snap waits MS for the pulse"}}},
      {"format", {"CAM", "FORMAT"}, {}, {{"format CAM mono8|bgr8", "output pixel format"}}},
      {"trigger", {"CAM"}, {}, {{"trigger CAM", "acquire one frame; prints its sequence number"}}},
      {"stats", {}, {"CAM"}, {{"stats [CAM]", "frames, drops, errors, reconnects, fps"}}},
      {"features", {"CAM"}, {}, {{"features CAM", "the camera's features: types, values, ranges"}}},
      {"get", {"CAM", "FEATURE"}, {}, {{"get CAM FEATURE", "a feature's current value"}}},
      {"set",
       {"CAM", "FEATURE", "VALUE"},
       {},
       {{"set CAM FEATURE VALUE", "set a feature; prints the value the camera took"}}},
      {"open", {"CAM"}, {}, {{"open CAM", "open the stream (takes the device)"}}},
      {"close", {"CAM"}, {}, {{"close CAM", "close the stream and release the device"}}},
      {"snap",
       {"CAM", "FILE"},
       {},
       {{"snap CAM FILE",
         "save the next frame; the extension of FILE\nnames the format (.png, .jpg, .tiff, ...)"}}},
      // X and Y are optional to CLI11 because --hide replaces them.
      {"target",
       {"CAM"},
       {"X", "Y"},
       {{"target CAM X Y",
         "synthetic camera: the simulated robot holds the\ncalibration target at robot X Y mm"},
        {"target CAM --hide", "synthetic camera: the robot takes the target away"}}},
  };
  return kSpecs;
}

const CommandSpec* findSpec(const std::string& name) {
  for (const CommandSpec& spec : commandSpecs()) {
    if (name == spec.name) return &spec;
  }
  return nullptr;
}

// Appends `help` after a first column `width` wide, continuation lines
// indented to the same column.
void appendEntry(std::string& text, const std::string& first, size_t width,
                 const std::string& help) {
  std::string line = "  " + first;
  line += std::string(width > first.size() ? width - first.size() : 1, ' ');
  size_t start = 0;
  while (true) {
    const size_t end = help.find('\n', start);
    text += line + help.substr(start, end - start) + '\n';
    if (end == std::string::npos) break;
    start = end + 1;
    line = std::string(width + 2, ' ');
  }
}

// The help of the whole tool, whichever command --help follows: the command
// list from commandSpecs(), the options from the CLI11 definition.
class CamHelpFormatter : public CLI::Formatter {
 public:
  std::string make_help(const CLI::App* app, std::string, CLI::AppFormatMode) const override {
    while (app->get_parent() != nullptr) app = app->get_parent();
    std::string text = std::string("usage: ") + kProgram +
                       " [--control ENDPOINT] [--timeout MS] [--json] COMMAND [ARGS]\n\n" +
                       app->get_description() + "\n\ncommands:\n";
    for (const CommandSpec& spec : commandSpecs()) {
      for (const UsageLine& line : spec.usage) appendEntry(text, line.synopsis, 32, line.help);
    }
    text += "\noptions:\n";
    for (const CLI::Option* option : app->get_options()) {
      std::string names = option->get_name(false, true);
      if (option->get_type_size() != 0) names += " " + option->get_type_name();
      appendEntry(text, names, 20, option->get_description());
    }
    return text + "\n" + app->get_footer() + "\n";
  }
};

// A CLI11 check whose message is what `check` returns for a bad value (empty
// when the value is good). This tool declares its commands with CLI11 itself
// (subcommands, its own help layout), which picksight::cli does not wrap.
CLI::Validator checkValue(std::function<std::string(const std::string&)> check) {
  return CLI::Validator([check = std::move(check)](std::string& value) { return check(value); },
                        "");
}

// Whether `word` is meant as an option rather than a value: "-5" is a word,
// so that roi can say why a negative X is wrong.
bool looksLikeOption(const std::string& word) {
  return word.size() >= 2 && word[0] == '-' &&
         (word[1] == '-' || std::isalpha(static_cast<unsigned char>(word[1])));
}

// The option of mode's argument LINE, ACTIVATION or TRIGGER_TIMEOUT.
std::string triggerOptionName(const std::string& arg) {
  if (arg == "LINE") return "line";
  if (arg == "ACTIVATION") return "activation";
  return "trigger-timeout";
}

// "CMD: missing arguments; usage: ..." for the command CLI11 was parsing.
Error missingArguments(const std::string& command) {
  return usageError(command + ": missing arguments; usage: " + kProgram + " " +
                    commandSynopsis(command));
}

}  // namespace

const std::string& CamCommand::arg(const std::string& name) const {
  static const std::string kEmpty;
  const auto it = args.find(name);
  return it == args.end() ? kEmpty : it->second;
}

std::string commandSynopsis(const std::string& command) {
  const CommandSpec* spec = findSpec(command);
  if (spec == nullptr) return command;
  std::string synopsis;
  for (const UsageLine& line : spec->usage) {
    synopsis += (synopsis.empty() ? "" : " | ") + std::string(line.synopsis);
  }
  return synopsis;
}

// Long because it declares every subcommand and option, in the order
// --help lists them, beside the checks CLI11 cannot make; split, the help
// and its options would no longer read side by side.
Result<CamOptions> parseCommandLine(const std::vector<std::string>& args) {
  CamOptions options;
  CLI::App app(
      "Configures the cameras of a running picksight-video-server through its\n"
      "control socket.",
      kProgram);
  app.formatter(std::make_shared<CamHelpFormatter>());
  app.footer(
      "Errors go to stderr. Exit codes: 0 ok, 1 server or camera error,\n"
      "2 usage error, 3 the server did not answer in time.");
  app.set_help_flag("-h,--help", "print this help");
  // Extras are reported by parse() below, with the messages scripts rely on.
  app.allow_extras();
  app.require_subcommand(0, 1);

  app.add_option("--control", options.endpoint,
                 std::string("the server's control socket (default ") + kDefaultEndpoint + ")")
      ->type_name("ENDPOINT")
      ->check(checkValue([](const std::string& v) {
        return v.empty() ? std::string("ENDPOINT must not be empty") : std::string();
      }));
  long long timeout_ms = kDefaultTimeout.count();
  app.add_option("--timeout", timeout_ms,
                 "how long to wait for an answer (default " +
                     std::to_string(kDefaultTimeout.count()) + ";\nsnap waits at least " +
                     std::to_string(kSnapMinTimeout.count()) + ")")
      ->type_name("MS")
      ->check(checkValue([](const std::string& v) {
        const std::optional<long long> ms = parseInt(v);
        if (ms && *ms > 0 && *ms <= std::numeric_limits<int>::max()) return std::string();
        return "MS must be a positive integer, got '" + v + "'";
      }));
  app.add_flag("--json", options.json, "print one JSON object on stdout, for scripts");
  CLI::Option* server_key = app.add_option("--curve-server-key", options.curve_server_key,
                                           "talk CURVE to the server: its public NAME.key")
                                ->type_name("FILE");
  app.add_option("--curve-key", options.curve_key,
                 "this client's NAME.key_secret, for a server\nwith an allow-list "
                 "(default: a fresh key pair)")
      ->type_name("FILE")
      ->needs(server_key);

  // Storage for the positionals, one map per command; std::map nodes stay
  // put, so CLI11 can hold pointers into them.
  std::map<std::string, std::map<std::string, std::string>> words;
  std::map<std::string, CLI::Option*> positionals;
  std::string scale;
  bool hide = false;
  // mode ... hardware: stored under these argument names when given.
  std::map<std::string, std::string> trigger_options;
  for (const CommandSpec& spec : commandSpecs()) {
    CLI::App* sub = app.add_subcommand(spec.name, spec.usage.front().help);
    sub->set_help_flag();  // --help after a command is the tool's help
    sub->fallthrough();    // global options after the command
    for (const char* name : spec.required) {
      positionals[std::string(spec.name) + " " + name] =
          sub->add_option(name, words[spec.name][name])->required();
    }
    for (const char* name : spec.optional) {
      positionals[std::string(spec.name) + " " + name] =
          sub->add_option(name, words[spec.name][name]);
    }
    if (std::string(spec.name) == "size") sub->add_option("--scale", scale)->type_name("S");
    if (std::string(spec.name) == "target") sub->add_flag("--hide", hide);
    if (std::string(spec.name) == "mode") {
      sub->add_option("--line", trigger_options["LINE"])->type_name("L");
      sub->add_option("--activation", trigger_options["ACTIVATION"])->type_name("EDGE");
      sub->add_option("--trigger-timeout", trigger_options["TRIGGER_TIMEOUT"])->type_name("MS");
    }
  }

  try {
    app.parse(std::vector<std::string>(args.rbegin(), args.rend()));
  } catch (const CLI::CallForHelp&) {
    options.help_text = app.help();
    return options;
  } catch (const CLI::ParseError& e) {
    const std::vector<CLI::App*> selected = app.get_subcommands();
    if (dynamic_cast<const CLI::RequiredError*>(&e) != nullptr && !selected.empty()) {
      return missingArguments(selected.front()->get_name());
    }
    const std::string what = e.what();
    if (dynamic_cast<const CLI::ArgumentMismatch*>(&e) != nullptr) {
      return usageError(what.substr(0, what.find(':')) + ": missing value");
    }
    return usageError(what);  // validators' messages start with the option
  }
  const std::vector<CLI::App*> selected = app.get_subcommands();
  const std::vector<std::string> extras = app.remaining();
  if (!extras.empty() && looksLikeOption(extras.front())) {
    return usageError("unknown option '" + extras.front() + "'");
  }
  if (selected.empty()) {
    if (!extras.empty()) return usageError("unknown command '" + extras.front() + "'");
    return usageError("missing command");
  }
  const std::string name = selected.front()->get_name();
  if (!extras.empty()) {
    return usageError(name + ": too many arguments (unexpected '" + extras.front() + "')");
  }
  options.timeout = std::chrono::milliseconds(timeout_ms);
  options.command.name = name;
  for (const auto& [key, option] : positionals) {
    const std::string command = key.substr(0, key.find(' '));
    const std::string arg = key.substr(key.find(' ') + 1);
    if (command == name && option->count() > 0) options.command.args[arg] = words[command][arg];
  }
  if (name == "size") {
    // Either "W H" or "--scale S": a lone W is as incomplete as a missing H.
    if (!scale.empty() || selected.front()->get_option("--scale")->count() > 0) {
      if (options.command.has("W")) {
        return usageError("size: too many arguments (unexpected '" + options.command.arg("W") +
                          "')");
      }
      options.command.args["S"] = scale;
    } else if (!options.command.has("H")) {
      return missingArguments(name);
    }
  }
  if (name == "mode") {
    for (const auto& [arg, value] : trigger_options) {
      if (selected.front()->get_option("--" + triggerOptionName(arg))->count() == 0) continue;
      if (options.command.arg("MODE") != "hardware") {
        return usageError("mode: --" + triggerOptionName(arg) + " goes with the hardware mode");
      }
      options.command.args[arg] = value;
    }
  }
  if (name == "target") {
    // Either "X Y" or "--hide".
    if (hide) {
      if (options.command.has("X")) {
        return usageError("target: too many arguments (unexpected '" + options.command.arg("X") +
                          "')");
      }
      options.command.args["HIDE"] = "1";
    } else if (!options.command.has("Y")) {
      return missingArguments(name);
    }
  }
  return options;
}

}  // namespace picksight::cam
