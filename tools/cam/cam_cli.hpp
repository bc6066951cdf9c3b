// picksight-cam: the camera configuration CLI as a library, so that tests can run
// it against an in-process control socket and read what it prints.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include <zmq.hpp>

#include "picksight/common/result.hpp"

namespace picksight::cam {

// Why the CLI failed on its own side: usage errors (nothing was sent), and
// replies it could not use or save. Printed and turned into exit codes.
enum class CliErrc { kUsage = 1, kBadReply, kSaveFailed };
const char* errorName(CliErrc e);
PICKSIGHT_ERROR_DOMAIN(CliErrc, "picksight-cam")

// Exit codes, part of the CLI's contract with scripts.
constexpr int kExitOk = 0;
constexpr int kExitServerError = 1;  // the server refused, or answered nonsense
constexpr int kExitUsage = 2;        // nothing was sent to any server
constexpr int kExitTimeout = 3;      // the server did not answer in time

// Usage errors are carried in Result as CliErrc::kUsage (exit code kExitUsage).
inline Error usageError(std::string message) {
  return makeError(CliErrc::kUsage, std::move(message));
}

// Runs one command: `args` without the program name. Output for the user or
// script goes to `out`, diagnostics to `err`; returns one of the exit codes.
// `ctx` is borrowed for the call only.
int runCamCli(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
              zmq::context_t& ctx);

}  // namespace picksight::cam

PICKSIGHT_ERROR_ENUM(picksight::cam::CliErrc)
