// picksight-cam: parses the command line, sends the one control request it
// stands for through ControlClient, and hands the reply to the printer.
#include "cam_cli.hpp"

#include <algorithm>
#include <optional>
#include <sstream>

#include "cam_command_line.hpp"
#include "picksight/transport/control_client.hpp"
#include "reply_printer.hpp"
#include "request_builder.hpp"

namespace picksight::cam {

using transport::ControlClient;
using transport::ControlErrc;
using transport::CurveClientKeys;
using transport::loadClientKeys;

const char* errorName(CliErrc e) {
  return e == CliErrc::kUsage ? "usage" : e == CliErrc::kBadReply ? "bad reply" : "save failed";
}

namespace {

std::string errorCodeName(int code) {
  if (proto::Error::Code_IsValid(code)) {
    return proto::Error::Code_Name(static_cast<proto::Error::Code>(code));
  }
  return "UNKNOWN";
}

}  // namespace

int runCamCli(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
              zmq::context_t& ctx) {
  const std::string hint = std::string("run '") + kProgram + " --help' for usage\n";
  auto options = parseCommandLine(args);
  if (!options) {
    err << kProgram << ": " << options.error().message << '\n' << hint;
    return kExitUsage;
  }
  if (!options->help_text.empty()) {
    out << options->help_text;
    return kExitOk;
  }
  auto request = buildRequest(options->command);
  if (!request) {
    err << kProgram << ": " << request.error().message << '\n' << hint;
    return kExitUsage;
  }
  const std::string& command = options->command.name;
  const std::chrono::milliseconds timeout =
      request->has_snap() ? std::max(options->timeout, kSnapMinTimeout) : options->timeout;

  std::optional<CurveClientKeys> curve;
  if (!options->curve_server_key.empty()) {
    auto keys = loadClientKeys(options->curve_key, options->curve_server_key);
    if (!keys) {
      err << kProgram << ": " << keys.error().message << '\n';
      return kExitUsage;
    }
    curve = std::move(*keys);
  }
  std::optional<ControlClient> client;
  try {
    client.emplace(ctx, options->endpoint, timeout, curve);
  } catch (const zmq::error_t& e) {
    // connect() rejects malformed endpoints: the user's typo, not the server.
    err << kProgram << ": invalid endpoint '" << options->endpoint << "': " << e.what() << '\n';
    return kExitUsage;
  }

  std::optional<Result<proto::ControlReply>> reply;
  try {
    reply.emplace(client->call(*request));
  } catch (const zmq::error_t& e) {
    err << kProgram << ": " << command << ": " << e.what() << '\n';
    return kExitServerError;
  }
  if (!*reply) {
    const Error& error = reply->error();
    if (error.code == ControlErrc::kNoReply) {
      err << kProgram << ": no answer from " << options->endpoint << " within " << timeout.count()
          << " ms: is picksight-video-server running?\n";
      return kExitTimeout;
    }
    err << kProgram << ": " << command << ": " << error.message << " (server error "
        << errorCodeName(error.code.value()) << ", code " << error.code.value() << ")\n";
    return kExitServerError;
  }

  std::ostringstream text;  // nothing on `out` unless the whole reply printed
  if (auto printed = printReply(*request, reply->value(), *options, text); !printed) {
    err << kProgram << ": " << command << ": " << printed.error().message;
    if (printed.error().code == CliErrc::kBadReply) err << " from " << options->endpoint;
    err << '\n';
    return kExitServerError;
  }
  out << text.str();
  return kExitOk;
}

}  // namespace picksight::cam
