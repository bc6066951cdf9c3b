// Robot protocol core commands.
#include "picksight/vision_app/robot_protocol.hpp"

#include "picksight/common/text.hpp"

namespace picksight::app {
namespace {
constexpr const char* kVersion = "0.1.0";
}  // namespace

RobotProtocol::RobotProtocol(VisionService& vision) : vision_(vision) {
  table_.add("PING", "PING", [](const Request& r) {
    return r.args.empty() ? std::string("OK")
                          : errorReply(kBadArguments, "PING takes no arguments");
  });
  table_.add("VERSION", "VERSION", [](const Request&) { return std::string("OK ") + kVersion; });
  table_.add("HELP", "HELP", [this](const Request&) { return table_.help(); });
  table_.add("LOCATE", "LOCATE <type>", [this](const Request& r) { return locate(r); });
  table_.add("FRAME", "FRAME", [this](const Request& r) { return frame(r); });
}

std::string RobotProtocol::locate(const Request& request) {
  if (request.args.size() != 1) return errorReply(kBadArguments, "usage: LOCATE <type>");
  const auto type = parseType(request.args[0]);
  if (!type) {
    return errorReply(kBadArguments, "LOCATE: type must be an integer in [0, 9999], got '" +
                                         printable(request.args[0]) + "'");
  }
  auto outcome = vision_.locate(*type);
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
