// Blocking TCP client speaking the robot protocol: one request line out, one
// reply line back. What a robot controller does, for tests, demo and bench.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

#include "picksight/common/result.hpp"

namespace picksight::tool_support {

class LineClient {
 public:
  LineClient() = default;
  ~LineClient();
  LineClient(LineClient&& other) noexcept;
  LineClient& operator=(LineClient&& other) noexcept;
  LineClient(const LineClient&) = delete;
  LineClient& operator=(const LineClient&) = delete;

  static Result<LineClient> connect(const std::string& host, uint16_t port,
                                    std::chrono::milliseconds timeout);

  // Sends raw bytes (a request line must end with '\n').
  Result<void> sendRaw(const std::string& bytes);
  // Reads one line (without CR/LF); error on timeout or closed connection.
  Result<std::string> readLine(std::chrono::milliseconds timeout);
  // Sends `line` + '\n' and reads the reply line.
  Result<std::string> request(const std::string& line, std::chrono::milliseconds timeout);
  void close();
  bool isOpen() const { return fd_ >= 0; }
  // This end of the connection as the server names its peer, "a.b.c.d:port"
  // (an IPv4-mapped address as IPv4); empty when closed.
  std::string localEndpoint() const;

 private:
  explicit LineClient(int fd) : fd_(fd) {}
  int fd_ = -1;
  std::string buffer_;
};

}  // namespace picksight::tool_support
