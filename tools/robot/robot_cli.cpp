// picksight-robot's command line, connection and batch modes.
#include "robot_cli.hpp"

#include <cmath>

#include "picksight/cli/command_line.hpp"

namespace picksight::robot {

using tool_support::LineClient;

namespace {

bool isOkReply(const std::string& reply) { return reply == "OK" || reply.rfind("OK ", 0) == 0; }

}  // namespace

Result<RobotOptions> parseCommandLine(const std::vector<std::string>& args) {
  RobotOptions o;
  double timeout_s = static_cast<double>(o.timeout.count()) / 1000.0;
  cli::App app(
      "Sends robot-protocol requests to a PickSight vision app and prints the replies.\n"
      "With no REQUEST: reads requests from stdin, one per line, or, on a terminal,\n"
      "prompts with line editing and history (~/.picksight_robot_history).\n"
      "Exit code: 0 every reply OK, 1 an ERROR reply, 2 bad usage or no connection.",
      kProgram);
  app.setHelpFlag("-h,--help", "print this help");
  app.addOption("--host", o.host, "vision app host name or address")
      ->typeName("HOST")
      ->showDefault();
  app.addOption("--port", o.port, "robot port")
      ->typeName("PORT")
      ->check(cli::range(1, 65535))
      ->showDefault();
  app.addOption("--timeout", timeout_s, "seconds to wait for a connection or a reply")
      ->typeName("S")
      ->check(cli::checkValue([](const std::string& v) {
        char* end = nullptr;
        const double d = std::strtod(v.c_str(), &end);
        return (end && *end == '\0' && std::isfinite(d) && d > 0 && d <= 3600)
                   ? std::string()
                   : std::string("a number of seconds in (0, 3600]");
      }))
      ->showDefault();
  app.addOption("request", o.commands, "request lines, e.g. 'LOCATE 1' (one per argument)")
      ->typeName("REQUEST");
  bool help = false;
  if (auto ok = cli::parseArgs(app, args, &help); !ok) return ok.error();
  if (help) {
    o.help_text = app.help();
    return o;
  }
  for (const auto& c : o.commands) {
    if (c.find_first_of("\r\n") != std::string::npos) {
      return makeError(cli::CommandLineErrc::kBadOption,
                       "a request may not hold a line break: give each one as its own argument");
    }
  }
  o.timeout = std::chrono::milliseconds(static_cast<long long>(std::ceil(timeout_s * 1000.0)));
  return o;
}

std::string RobotSession::peer() const {
  return options_.host + ":" + std::to_string(options_.port);
}

int RobotSession::send(const std::string& request, std::ostream& out, std::ostream& err) {
  // A connection the server closed (idle time, restart) is only seen when
  // used: then connect again once and resend, since nothing was answered.
  for (int attempt = 0; attempt < 2; ++attempt) {
    const bool fresh = !client_;
    if (fresh) {
      auto c = LineClient::connect(options_.host, options_.port, options_.timeout);
      if (!c) {
        err << kProgram << ": " << c.error().message << "\n";
        return kExitFailure;
      }
      client_.emplace(std::move(*c));
    }
    auto sent = client_->sendRaw(request + "\n");
    Result<std::string> reply =
        sent ? client_->readLine(options_.timeout) : Result<std::string>(sent.error());
    if (reply) {
      out << *reply << "\n" << std::flush;
      return isOkReply(*reply) ? kExitOk : kExitErrorReply;
    }
    client_.reset();
    // A timeout is an answer that did not come, not a stale connection:
    // resending could run the request twice.
    const bool timed_out = reply.error().code == std::errc::timed_out;
    if (fresh || timed_out) {
      err << kProgram << ": " << peer() << ": " << reply.error().message << "\n";
      return kExitFailure;
    }
  }
  return kExitFailure;
}

bool isComment(const std::string& line) {
  const auto first = line.find_first_not_of(" \t\r");
  return first == std::string::npos || line[first] == '#';
}

int runCommands(RobotSession& session, const std::vector<std::string>& commands, std::ostream& out,
                std::ostream& err) {
  int status = kExitOk;
  for (const auto& c : commands) {
    const int s = session.send(c, out, err);
    if (s == kExitFailure) return s;
    if (s != kExitOk) status = s;
  }
  return status;
}

int runScript(RobotSession& session, std::istream& in, std::ostream& out, std::ostream& err) {
  int status = kExitOk;
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (isComment(line)) continue;
    const int s = session.send(line, out, err);
    if (s == kExitFailure) return s;
    if (s != kExitOk) status = s;
  }
  return status;
}

}  // namespace picksight::robot
