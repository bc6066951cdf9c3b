// The TCP server robot controllers connect to: one request line in, one
// reply line out, synchronous per connection, many connections at once.
//
// Bounds, so that idle, slow or hostile clients cannot lock a robot out:
// peers outside the allow-list get one ERROR 15 line and are closed (logged
// once per address); at most max_connections connections, and at most
// max_per_address from one address (ERROR 13, closed); a connection that
// completes no request line for idle_timeout gets ERROR 16 and is closed
// (a client trickling bytes without ending a line is idle too); a line over
// max_line gets ERROR 12 and is skipped.
//
// Threading: one accept thread and one thread per connection. The handler is
// called concurrently from connection threads and must be thread-safe.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <list>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <string_view>
#include <thread>

#include "picksight/common/allow_list.hpp"
#include "picksight/protocol/session.hpp"

namespace picksight::app {

struct RobotServerOptions {
  // Every interface: robot controllers are other machines on the cell's
  // network. Limit who may connect with `allow` (docs/SECURITY.md).
  std::string bind_address = "0.0.0.0";
  uint16_t port = 5600;         // 0 = any free port (read it back with port())
  size_t max_line = 4096;       // longer requests get ERROR 12
  size_t max_connections = 64;  // more get ERROR 13 and are closed
  // From one address; half the total, so that one host (a misbehaving
  // gateway, a scan) leaves room for the others. 0 = no limit of its own.
  size_t max_per_address = 32;
  // No complete request for this long: ERROR 16 and closed. 0 = never.
  std::chrono::milliseconds idle_timeout{60000};
  AllowList allow;  // empty: everyone
  // Names the port in each session's client ("robot 10.0.0.5:41234").
  std::string label = "robot";
};

class RobotServer {
 public:
  // Returns the reply line for one request line (without line ending).
  using Handler = std::function<std::string(std::string_view line)>;
  // The same with the connection's session (see session.hpp); the server
  // runs session.after_reply once the reply is sent.
  using SessionHandler = std::function<std::string(std::string_view line, Session& session)>;

  // Binds and listens at once; throws std::runtime_error naming the port.
  RobotServer(RobotServerOptions options, Handler handler);
  RobotServer(RobotServerOptions options, SessionHandler handler);
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
    std::string peer;  // address, for the per-address count
    uint16_t peer_port = 0;
    std::thread thread;
    std::atomic<bool> done{false};
  };

  void acceptLoop();
  // Admits a new connection or answers why not and closes it.
  void admit(int fd, const std::string& peer, uint16_t peer_port, bool allowed);
  void serve(Connection& connection);
  void reapFinished();

  const RobotServerOptions options_;
  const SessionHandler handler_;
  int listen_fd_ = -1;
  uint16_t port_ = 0;
  std::thread accept_thread_;
  std::atomic<bool> stop_{false};
  std::atomic<size_t> active_{0};

  // Addresses whose refusal was logged (accept thread only; bounded).
  std::set<std::string> refused_logged_;

  std::mutex mutex_;  // guards connections_ and per_address_
  std::list<Connection> connections_;
  std::map<std::string, size_t> per_address_;  // open connections by peer address
};

}  // namespace picksight::app
