// picksight-cam's command line, defined with CLI11: global options, one
// subcommand per control request, and the help text generated from them.
#pragma once

#include <chrono>
#include <map>
#include <string>
#include <vector>

#include "picksight/common/result.hpp"

namespace picksight::cam {

constexpr const char* kProgram = "picksight-cam";
constexpr const char* kDefaultEndpoint = "tcp://127.0.0.1:5556";
constexpr std::chrono::milliseconds kDefaultTimeout{2000};
// Least time a snap waits for its answer: the server itself waits for the
// next frame (up to 3 s) before it replies, so the usual timeout is too short.
constexpr std::chrono::milliseconds kSnapMinTimeout{5000};

// One subcommand with the words given for its positional arguments, by
// argument name ("CAM", "X", "FEATURE", ...); optional ones left out are absent.
struct CamCommand {
  std::string name;
  std::map<std::string, std::string> args;

  bool has(const std::string& arg) const { return args.count(arg) > 0; }
  // The word given for `arg`; empty when absent.
  const std::string& arg(const std::string& name) const;
};

struct CamOptions {
  std::string endpoint = kDefaultEndpoint;
  std::chrono::milliseconds timeout = kDefaultTimeout;
  bool json = false;
  // CURVE (docs/SECURITY.md): the server's public key file, and this
  // client's secret key file (empty: a fresh pair). Both empty: plain.
  std::string curve_server_key;
  std::string curve_key;
  // Set when --help was given: print it and do nothing else.
  std::string help_text;
  CamCommand command;
};

// Parses `args` (without the program name). Global options are accepted before
// and after the command ("list --json"); "--" after the command lets a word
// start with a dash. Errors are usage errors (code kExitUsage) whose message
// names the command or option at fault.
Result<CamOptions> parseCommandLine(const std::vector<std::string>& args);

// The usage line of `command` ("roi CAM X Y W H"), alternatives joined by " | ".
std::string commandSynopsis(const std::string& command);

}  // namespace picksight::cam
