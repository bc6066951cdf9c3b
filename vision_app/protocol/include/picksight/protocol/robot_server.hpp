// The TCP server robot controllers connect to: one request line in, one
// reply line out, synchronous per connection, many connections at once.
//
// Bounds, so that idle, slow or hostile clients cannot lock a robot out
// (admission is TcpListener's, as on the Modbus port): peers outside the
// allow-list get one ERROR 15 line and are closed; beyond max_connections,
// or max_per_address from one address, ERROR 13 and closed; a connection
// that completes no request line for idle_timeout gets ERROR 16 and is
// closed (a client trickling bytes without ending a line is idle too); a
// line over max_line gets ERROR 12 and is skipped.
//
// Threading: one accept thread and one thread per connection. The handler is
// called concurrently from connection threads and must be thread-safe.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <list>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>

#include "picksight/common/tcp_listener.hpp"
#include "picksight/protocol/session.hpp"

namespace picksight::protocol {

struct RobotServerOptions {
  // Where and whom: the admission policy every PickSight port shares. Every
  // interface by default: robot controllers are other machines on the
  // cell's network. Limit who may connect with `listen.allow`
  // (docs/SECURITY.md); port 0 = any free port (read it back with port()).
  TcpListenerOptions listen = [] {
    TcpListenerOptions o;
    o.port = 5600;
    return o;
  }();
  size_t max_line = 4096;  // longer requests get ERROR 12
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

  uint16_t port() const { return listener_.port(); }
  void start();
  void stop();
  size_t connections() const { return listener_.connections(); }

 private:
  struct Connection {
    explicit Connection(TcpListener::Connection accepted) : link(std::move(accepted)) {}
    TcpListener::Connection link;  // closed when reaped, after the thread is joined
    std::thread thread;
    std::atomic<bool> done{false};
  };

  void acceptLoop();
  void serve(Connection& connection);
  void reapFinished();

  const RobotServerOptions options_;
  const SessionHandler handler_;
  TcpListener listener_;
  std::thread accept_thread_;
  std::atomic<bool> stop_{false};

  std::mutex mutex_;  // guards connections_
  std::list<Connection> connections_;
};

}  // namespace picksight::protocol
