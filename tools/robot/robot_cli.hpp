// picksight-robot: the robot protocol from a shell, as a library so that the
// tests can run its batch modes on streams and read what it prints.
#pragma once

#include <chrono>
#include <cstdint>
#include <istream>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "picksight/common/result.hpp"
#include "picksight/tool_support/line_client.hpp"

namespace picksight::robot {

constexpr const char* kProgram = "picksight-robot";

// Exit codes, part of the tool's contract with scripts.
constexpr int kExitOk = 0;
constexpr int kExitErrorReply = 1;  // the vision app answered ERROR (or not OK)
constexpr int kExitFailure = 2;     // bad usage, no connection, no reply in time

struct RobotOptions {
  std::string host = "127.0.0.1";
  uint16_t port = 5600;
  std::chrono::milliseconds timeout{10000};
  // Requests given as arguments, one per argument; empty: read them from
  // stdin (lines) or the terminal (interactive).
  std::vector<std::string> commands;
  // Set when --help was given: print it and do nothing else.
  std::string help_text;
};

// Parses `args` (without the program name). Errors name the option at fault;
// a request holding a line break is refused (it would be two requests whose
// second reply nobody reads).
Result<RobotOptions> parseCommandLine(const std::vector<std::string>& args);

// One connection to a vision app, opened on the first request and again
// after it was lost (the next request reconnects once). Used by one thread.
class RobotSession {
 public:
  explicit RobotSession(RobotOptions options) : options_(std::move(options)) {}

  // Sends `request`, prints the reply line to `out` (diagnostics to `err`);
  // returns kExitOk for an OK reply, kExitErrorReply for any other reply,
  // kExitFailure when there was no reply.
  int send(const std::string& request, std::ostream& out, std::ostream& err);
  const RobotOptions& options() const { return options_; }
  // "host:port", for prompts and messages.
  std::string peer() const;

 private:
  RobotOptions options_;
  std::optional<tool_support::LineClient> client_;
};

// True for lines a script or a person types that are not requests: blank
// lines and comments ('#').
bool isComment(const std::string& line);

// Sends `commands` in order on one connection. Stops at the first failure
// (kExitFailure); otherwise kExitErrorReply when any reply was not OK.
int runCommands(RobotSession& session, const std::vector<std::string>& commands, std::ostream& out,
                std::ostream& err);

// Sends each line of `in` (blank lines and comments skipped), as runCommands.
int runScript(RobotSession& session, std::istream& in, std::ostream& out, std::ostream& err);

}  // namespace picksight::robot
