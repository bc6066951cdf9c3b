// The TCP server robot controllers connect to: one request line in, one
// reply line out, synchronous per connection, many connections at once.
//
// Threading: one accept thread and one thread per connection. The handler is
// called concurrently from connection threads and must be thread-safe.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <list>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>

namespace picksight::app {

struct RobotServerOptions {
  std::string bind_address = "0.0.0.0";
  uint16_t port = 5600;         // 0 = any free port (read it back with port())
  size_t max_line = 4096;       // longer requests get ERROR 12
  size_t max_connections = 64;  // more get ERROR 13 and are closed
};

class RobotServer {
 public:
  // Returns the reply line for one request line (without line ending).
  using Handler = std::function<std::string(std::string_view line)>;

  // Binds and listens at once; throws std::runtime_error naming the port.
  RobotServer(RobotServerOptions options, Handler handler);
  ~RobotServer();
  RobotServer(const RobotServer&) = delete;
  RobotServer& operator=(const RobotServer&) = delete;

  uint16_t port() const { return port_; }
  void start();
  void stop();
  size_t connections() const { return active_.load(); }

 private:
  struct Connection {
    int fd = -1;
    std::thread thread;
    std::atomic<bool> done{false};
  };

  void acceptLoop();
  void serve(Connection& connection);
  void reapFinished();

  const RobotServerOptions options_;
  const Handler handler_;
  int listen_fd_ = -1;
  uint16_t port_ = 0;
  std::thread accept_thread_;
  std::atomic<bool> stop_{false};
  std::atomic<size_t> active_{0};

  std::mutex mutex_;  // guards connections_
  std::list<Connection> connections_;
};

}  // namespace picksight::app
