// Robot protocol core commands.
#include "picksight/protocol/robot_protocol.hpp"

#include "picksight/common/text.hpp"

namespace picksight::protocol {

using cell::VisionService;

namespace {
constexpr const char* kVersion = "0.1.0";
}  // namespace

RobotProtocol::RobotProtocol(VisionService& vision) : vision_(vision) {
  table_.add(
      "PING", "PING",
      [](const Request& r) {
        return r.args.empty() ? std::string("OK")
                              : errorReply(ProtocolErrc::kBadArguments, "PING takes no arguments");
      },
      neverChanges);
  table_.add(
      "VERSION", "VERSION", [](const Request&) { return std::string("OK ") + kVersion; },
      neverChanges);
  table_.add(
      "HELP", "HELP", [this](const Request&) { return table_.help(); }, neverChanges);
  table_.add(
      "FRAME", "FRAME", [this](const Request& r) { return frame(r); }, neverChanges);
}

std::string RobotProtocol::frame(const Request& request) {
  if (!request.args.empty())
    return errorReply(ProtocolErrc::kBadArguments, "FRAME takes no arguments");
  const auto f = vision_.lastFrame();
  if (!f) return errorReply(link::CameraErrc::kNoFrame, "no frame used yet");
  return "OK " + f->camera + " " + std::to_string(f->sequence) + " " +
         std::to_string(f->host_timestamp_ns) + " " + std::to_string(f->width) + " " +
         std::to_string(f->height) + " " + (f->triggered ? "1" : "0");
}

}  // namespace picksight::protocol
