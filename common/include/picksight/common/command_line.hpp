// Runs a CLI11 parser over argv words and reports the outcome as a Result
// whose message names the option at fault, as the tools' scripts expect.
// Header-only: include it only from targets that link CLI11::CLI11.
#pragma once

#include <functional>
#include <iostream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "picksight/common/result.hpp"

namespace picksight {

// A command line a tool cannot use; the message names the option.
enum class CommandLineErrc { kBadOption = 1 };
inline const char* errorName(CommandLineErrc) { return "bad option"; }
PICKSIGHT_ERROR_DOMAIN(CommandLineErrc, "command line")

// A CLI11 check whose message is what `check` returns for a bad value (empty
// when the value is good); CLI11 puts the option's name in front of it.
inline CLI::Validator checkValue(std::function<std::string(const std::string&)> check,
                                 std::string value_name = "") {
  return CLI::Validator([check = std::move(check)](std::string& value) { return check(value); },
                        std::move(value_name));
}

// Parses `args` (argv without the program name) with `app`. -h/--help sets
// *help (when not null) and succeeds without checking anything else. Errors
// carry `code` (an error enum of the caller's domain); their message starts
// with the option ("--fps: ...", "unknown option '--speed'", "--fps: missing
// value").
template <typename E = CommandLineErrc>
Result<void> parseArgs(CLI::App& app, const std::vector<std::string>& args, bool* help,
                       E code = CommandLineErrc::kBadOption) {
  if (help) *help = false;
  try {
    app.parse(std::vector<std::string>(args.rbegin(), args.rend()));  // CLI11 pops from the back
  } catch (const CLI::CallForHelp&) {
    if (help) *help = true;
    return {};
  } catch (const CLI::ExtrasError&) {
    const std::vector<std::string> extras = app.remaining();
    return makeError(code, "unknown option '" + (extras.empty() ? "" : extras.front()) + "'");
  } catch (const CLI::ArgumentMismatch& e) {
    const std::string what = e.what();
    return makeError(code, what.substr(0, what.find(':')) + ": missing value");
  } catch (const CLI::ParseError& e) {
    return makeError(code, e.what());
  }
  return {};
}

// For a tool's main(): parses argv with `app`. --help prints the help on
// stdout and gives exit code 0; a bad option prints the error and the help on
// stderr and gives 2; nullopt when the tool should go on.
inline std::optional<int> parseMainArgs(CLI::App& app, int argc, char** argv) {
  bool help = false;
  auto ok = parseArgs(app, std::vector<std::string>(argv + 1, argv + argc), &help);
  if (help) {
    std::cout << app.help();
    return 0;
  }
  if (!ok) {
    std::cerr << app.get_name() << ": " << ok.error().message << "\n\n" << app.help();
    return 2;
  }
  return std::nullopt;
}

}  // namespace picksight

PICKSIGHT_ERROR_ENUM(picksight::CommandLineErrc)
