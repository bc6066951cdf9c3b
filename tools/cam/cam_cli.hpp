// picksight-cam: the camera configuration CLI as a library, so that tests can run
// it against an in-process control socket and read what it prints.
#pragma once

#include <chrono>
#include <cstdint>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include <zmq.hpp>

#include "picksight.pb.h"
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

constexpr const char* kDefaultEndpoint = "tcp://127.0.0.1:5556";
constexpr std::chrono::milliseconds kDefaultTimeout{2000};
// Least time a snap waits for its answer: the server itself waits for the
// next frame (up to 3 s) before it replies, so the usual timeout is too short.
constexpr std::chrono::milliseconds kSnapMinTimeout{5000};

struct CamOptions {
  std::string endpoint = kDefaultEndpoint;
  std::chrono::milliseconds timeout = kDefaultTimeout;
  bool json = false;
  bool help = false;
  std::vector<std::string> command;  // the command word and its arguments
};

// Splits global options (accepted anywhere before a "--") from the command
// words. Errors are usage errors, with the message to print.
Result<CamOptions> parseOptions(const std::vector<std::string>& args);

// Turns the command words into the control request they stand for, checking
// argument counts and numbers. Errors are usage errors.
Result<proto::ControlRequest> buildRequest(const std::vector<std::string>& command);

std::string usageText();

// Runs one command: `args` without the program name. Output for the user or
// script goes to `out`, diagnostics to `err`; returns one of the exit codes.
// `ctx` is borrowed for the call only.
int runCamCli(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
              zmq::context_t& ctx);

// JSON string literal body for `text`: quotes, backslashes and control
// characters escaped; other bytes (UTF-8) pass through.
std::string escapeJson(std::string_view text);

// Minimal streaming JSON writer: enough for the flat objects this tool prints,
// and no new dependency. Commas are placed automatically; the caller is
// responsible for balanced begin/end calls and for key() inside objects.
class JsonWriter {
 public:
  JsonWriter& beginObject();
  JsonWriter& endObject();
  JsonWriter& beginArray();
  JsonWriter& endArray();
  JsonWriter& key(std::string_view name);
  JsonWriter& string(std::string_view value);
  JsonWriter& uinteger(std::uint64_t value);
  // Shortest text that reads back to the same double; null for NaN/infinity,
  // which JSON cannot represent.
  JsonWriter& real(double value);
  JsonWriter& boolean(bool value);

  const std::string& str() const { return text_; }

 private:
  void separate();

  std::string text_;
  // One entry per open object/array: whether it already holds an element.
  std::vector<bool> has_element_;
  bool after_key_ = false;
};

}  // namespace picksight::cam

PICKSIGHT_ERROR_ENUM(picksight::cam::CliErrc)
