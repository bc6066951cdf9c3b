// Parses a tool's command line (picksight::cli, CLI11 behind it) and
// reports the outcome as a Result whose message names the option at fault,
// as the tools' scripts expect.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "picksight/cli/options.hpp"
#include "picksight/common/result.hpp"

namespace picksight::cli {

// A command line a tool cannot use; the message names the option.
enum class CommandLineErrc { kBadOption = 1 };
inline const char* errorName(CommandLineErrc) { return "bad option"; }
PICKSIGHT_ERROR_DOMAIN(CommandLineErrc, "command line")

// A check whose message is what `check` returns for a bad value (empty when
// the value is good); the parser puts the option's name in front of it.
Validator checkValue(std::function<std::string(const std::string&)> check,
                     std::string value_name = "");

// Parses `args` (argv without the program name) with `app`, as App::parse.
// Errors carry `code` (an error enum of the caller's domain).
template <typename E = CommandLineErrc>
Result<void> parseArgs(App& app, const std::vector<std::string>& args, bool* help,
                       E code = CommandLineErrc::kBadOption) {
  if (std::optional<std::string> error = app.parse(args, help)) {
    return makeError(code, std::move(*error));
  }
  return {};
}

// For a tool's main(): parses argv with `app`. --help prints the help on
// stdout and gives exit code 0; a bad option prints the error and the help on
// stderr and gives 2; nullopt when the tool should go on.
std::optional<int> parseMainArgs(App& app, int argc, char** argv);

}  // namespace picksight::cli

PICKSIGHT_ERROR_ENUM(picksight::cli::CommandLineErrc)
