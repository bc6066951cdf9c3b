// Robot protocol commands.
#include "picksight/vision_app/robot_protocol.hpp"

#include <algorithm>

#include "picksight/common/text.hpp"

namespace picksight::app {
namespace {
constexpr const char* kVersion = "0.1.0";
constexpr const char* kHelp =
    "OK commands: PING | LOCATE <type> | FRAME | VERSION | HELP (see docs/PROTOCOL.md)";

// Keeps a reply one line of printable text whatever a request contained.
std::string printable(std::string_view text, size_t limit = 40) {
  std::string out;
  for (char c : text.substr(0, limit)) {
    out += (static_cast<unsigned char>(c) >= 0x20 && static_cast<unsigned char>(c) < 0x7f) ? c : '?';
  }
  if (text.size() > limit) out += "...";
  return out;
}
}  // namespace

std::string errorReply(int code, const std::string& text) {
  return "ERROR " + std::to_string(code) + " " + text;
}

std::optional<Request> parseRequest(std::string_view line) {
  const auto fields = splitFields(line, " \t,");
  if (fields.empty()) return std::nullopt;
  Request r;
  r.command = toUpper(fields[0]);
  for (size_t i = 1; i < fields.size(); ++i) r.args.emplace_back(fields[i]);
  return r;
}

std::string RobotProtocol::handle(std::string_view line) {
  const auto request = parseRequest(line);
  if (!request) return errorReply(kEmptyRequest, "empty request");
  const std::string& c = request->command;
  if (c == "PING") {
    if (!request->args.empty()) return errorReply(kBadArguments, "PING takes no arguments");
    return "OK";
  }
  if (c == "LOCATE") return locate(*request);
  if (c == "FRAME") return frame(*request);
  if (c == "VERSION") return std::string("OK ") + kVersion;
  if (c == "HELP") return kHelp;
  return errorReply(kUnknownCommand, "unknown command '" + printable(c) + "' (try HELP)");
}

std::string RobotProtocol::locate(const Request& request) {
  if (request.args.size() != 1) return errorReply(kBadArguments, "usage: LOCATE <type>");
  const auto type = parseInt(request.args[0]);
  if (!type || *type < 0 || *type > 9999) {
    return errorReply(kBadArguments, "LOCATE: type must be an integer in [0, 9999], got '" +
                                         printable(request.args[0]) + "'");
  }
  auto outcome = vision_.locate();
  if (!outcome) return errorReply(outcome.error().code, outcome.error().message);
  std::string reply = "OK " + std::to_string(outcome->parts.size());
  for (const auto& p : outcome->parts) {
    reply += " " + formatFixed(p.x) + " " + formatFixed(p.y) + " " + formatFixed(p.angle_deg);
  }
  return reply;
}

std::string RobotProtocol::frame(const Request& request) {
  if (!request.args.empty()) return errorReply(kBadArguments, "FRAME takes no arguments");
  const auto f = vision_.lastFrame();
  if (!f) return errorReply(kNoFrame, "no frame used yet");
  return "OK " + f->camera + " " + std::to_string(f->sequence) + " " +
         std::to_string(f->host_timestamp_ns) + " " + std::to_string(f->width) + " " +
         std::to_string(f->height) + " " + (f->triggered ? "1" : "0");
}

}  // namespace picksight::app
