// Robot TCP server: a thread per connection; admission is TcpListener's,
// the bounded line framing LineFramer's.
#include "picksight/protocol/robot_server.hpp"

#include <poll.h>
#include <sys/socket.h>

#include <cerrno>

#include "picksight/common/log.hpp"
#include "picksight/common/text.hpp"
#include "picksight/protocol/command_table.hpp"
#include "picksight/protocol/line_framer.hpp"
#include "picksight/protocol/robot_errors.hpp"

namespace picksight::protocol {
namespace {
std::string errorLine(ProtocolErrc code, const std::string& text) {
  return errorReply(code, text) + "\n";
}

// A refused robot is told why in the protocol's words before it is closed.
std::string refusalLine(TcpListener::Refusal why, const std::string& text) {
  return errorLine(why == TcpListener::Refusal::kNotAllowed ? ProtocolErrc::kNotAllowed
                                                            : ProtocolErrc::kTooManyConnections,
                   text);
}
}  // namespace

RobotServer::RobotServer(RobotServerOptions options, Handler handler)
    : RobotServer(std::move(options),
                  [handler = std::move(handler)](std::string_view line, Session&) {
                    return handler(line);
                  }) {}

RobotServer::RobotServer(RobotServerOptions options, SessionHandler handler)
    : options_(std::move(options)),
      handler_(std::move(handler)),
      listener_(options_.label + " port", options_.listen, refusalLine) {}

RobotServer::~RobotServer() { stop(); }

void RobotServer::start() {
  if (accept_thread_.joinable()) return;
  stop_ = false;
  accept_thread_ = std::thread([this] { acceptLoop(); });
}

void RobotServer::stop() {
  stop_ = true;
  if (accept_thread_.joinable()) accept_thread_.join();
  // Joined outside the lock: a connection thread takes it on its way out.
  // Splicing keeps the nodes, which the threads still refer to.
  std::list<Connection> closing;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closing.splice(closing.end(), connections_);
    // Wake connection threads blocked in poll/recv.
    for (auto& c : closing) ::shutdown(c.link.fd(), SHUT_RDWR);
  }
  for (auto& c : closing) {
    if (c.thread.joinable()) c.thread.join();
  }
}

void RobotServer::reapFinished() {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto it = connections_.begin(); it != connections_.end();) {
    if (it->done) {
      it->thread.join();
      it = connections_.erase(it);  // closes the socket
    } else {
      ++it;
    }
  }
}

void RobotServer::acceptLoop() {
  while (!stop_) {
    pollfd p{listener_.fd(), POLLIN, 0};
    const int r = ::poll(&p, 1, 200);
    reapFinished();
    if (r <= 0) continue;
    auto accepted = listener_.accept();
    if (!accepted) continue;
    std::lock_guard<std::mutex> lock(mutex_);
    Connection& c = connections_.emplace_back(std::move(*accepted));
    c.thread = std::thread([this, &c] { serve(c); });
  }
}

void RobotServer::serve(Connection& connection) {
  const int fd = connection.link.fd();
  LineFramer framer(options_.max_line);
  const std::string too_long =
      errorLine(ProtocolErrc::kRequestTooLong,
                "request too long (limit " + std::to_string(options_.max_line) + " bytes)");
  using Clock = std::chrono::steady_clock;
  // Only a complete request (or an over-long one) counts as activity.
  Clock::time_point last_request = Clock::now();
  Session session;
  session.client = options_.label + " " + connection.link.peerAddress() + ":" +
                   std::to_string(connection.link.peerPort());
  const auto on_line = [&](std::string_view line) {
    last_request = Clock::now();
    session.received = last_request;
    session.after_reply = nullptr;
    std::string reply;
    try {
      reply = handler_(line, session);
    } catch (const std::exception& e) {
      // A bug in a command must cost one request, not the server.
      logError("robot request '", printable(line, 80), "': ", e.what());
      reply = "ERROR 99 internal error";
      session.after_reply = nullptr;
    }
    const bool sent = sendAll(fd, reply + "\n");
    // After the reply: what the request publishes never delays the robot.
    if (auto after = std::move(session.after_reply)) {
      session.after_reply = nullptr;
      try {
        after(reply);
      } catch (const std::exception& e) {
        logError("after robot request '", printable(line, 80), "': ", e.what());
      }
    }
    return sent;
  };
  const auto on_too_long = [&] {
    last_request = Clock::now();
    return sendAll(fd, too_long);
  };
  const auto idle = options_.listen.idle_timeout;
  char chunk[4096];
  while (!stop_) {
    pollfd p{fd, POLLIN, 0};
    const int r = ::poll(&p, 1, 200);
    if (idle.count() > 0 && Clock::now() - last_request >= idle) {
      sendAll(fd, errorLine(ProtocolErrc::kIdle, "no request for " +
                                                     formatFixed(idle.count() / 1000.0, 1) +
                                                     " s: connection closed"));
      break;
    }
    if (r == 0) continue;
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) break;
    const ssize_t n = ::recv(fd, chunk, sizeof(chunk), 0);
    if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    if (n <= 0) break;  // closed by the client, maybe mid-request: nothing to answer
    if (!framer.feed(std::string_view(chunk, static_cast<size_t>(n)), on_line, on_too_long)) break;
  }
  // The slot frees now; the socket when the thread is joined (stop() may
  // still shut it down until then).
  connection.link.releaseSlot();
  connection.done = true;
}

}  // namespace picksight::protocol
