// The robot protocol's commands (docs/PROTOCOL.md): parses one request line
// and produces its one reply line. Stateless per line, thread-safe.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "picksight/vision_app/vision_service.hpp"

namespace picksight::app {

// Protocol error codes (ERROR <code> <text>).
enum ProtocolError : int {
  kUnknownCommand = 10,
  kBadArguments = 11,
  kRequestTooLong = 12,  // sent by RobotServer
  kTooManyConnections = 13,  // sent by RobotServer
  kEmptyRequest = 14,
};

// A parsed request: the command word upper-cased and its arguments, split
// on spaces, tabs or commas.
struct Request {
  std::string command;
  std::vector<std::string> args;
};

// Nullopt for an empty or blank line.
std::optional<Request> parseRequest(std::string_view line);

class RobotProtocol {
 public:
  explicit RobotProtocol(VisionService& vision) : vision_(vision) {}
  std::string handle(std::string_view line);

 private:
  std::string locate(const Request& request);
  std::string frame(const Request& request);

  VisionService& vision_;
};

std::string errorReply(int code, const std::string& text);

}  // namespace picksight::app
