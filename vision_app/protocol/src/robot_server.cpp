// Robot TCP server: sockets and threads; the bounded line framing is
// LineFramer's.
#include "picksight/protocol/robot_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "picksight/common/log.hpp"
#include "picksight/common/text.hpp"
#include "picksight/protocol/command_table.hpp"
#include "picksight/protocol/line_framer.hpp"
#include "picksight/protocol/robot_errors.hpp"

namespace picksight::app {
namespace {
// One write per reply: with TCP_NODELAY the reply leaves in one segment.
bool sendAll(int fd, const std::string& data) {
  size_t sent = 0;
  while (sent < data.size()) {
    const ssize_t n = ::send(fd, data.data() + sent, data.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    sent += static_cast<size_t>(n);
  }
  return true;
}

// Refused addresses remembered for logging once each; beyond this many a
// scan of the network is not worth more memory.
constexpr size_t kMaxRefusedLogged = 1024;

std::string errorLine(ProtocolErrc code, const std::string& text) {
  return errorReply(code, text) + "\n";
}
}  // namespace

RobotServer::RobotServer(RobotServerOptions options, Handler handler)
    : RobotServer(std::move(options),
                  [handler = std::move(handler)](std::string_view line, Session&) {
                    return handler(line);
                  }) {}

RobotServer::RobotServer(RobotServerOptions options, SessionHandler handler)
    : options_(std::move(options)), handler_(std::move(handler)) {
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0)
    throw std::runtime_error(std::string("robot server: socket: ") + strerror(errno));
  int one = 1;
  ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(options_.port);
  if (::inet_pton(AF_INET, options_.bind_address.c_str(), &addr.sin_addr) != 1) {
    ::close(listen_fd_);
    throw std::runtime_error("robot server: bad bind address '" + options_.bind_address + "'");
  }
  if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0 ||
      ::listen(listen_fd_, 64) != 0) {
    const std::string why = strerror(errno);
    ::close(listen_fd_);
    throw std::runtime_error("robot server: cannot listen on port " +
                             std::to_string(options_.port) + ": " + why);
  }
  socklen_t len = sizeof(addr);
  ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
}

RobotServer::~RobotServer() {
  stop();
  if (listen_fd_ >= 0) ::close(listen_fd_);
}

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
    for (auto& c : closing) ::shutdown(c.fd, SHUT_RDWR);
  }
  for (auto& c : closing) {
    if (c.thread.joinable()) c.thread.join();
    ::close(c.fd);
  }
  std::lock_guard<std::mutex> lock(mutex_);
  per_address_.clear();
}

void RobotServer::reapFinished() {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto it = connections_.begin(); it != connections_.end();) {
    if (it->done) {
      it->thread.join();
      ::close(it->fd);
      it = connections_.erase(it);
    } else {
      ++it;
    }
  }
}

void RobotServer::acceptLoop() {
  while (!stop_) {
    pollfd p{listen_fd_, POLLIN, 0};
    const int r = ::poll(&p, 1, 200);
    reapFinished();
    if (r <= 0) continue;
    sockaddr_storage peer{};
    socklen_t peer_len = sizeof(peer);
    const int fd =
        ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&peer), &peer_len, SOCK_CLOEXEC);
    if (fd < 0) continue;
    int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
    const auto* address = reinterpret_cast<const sockaddr*>(&peer);
    uint16_t peer_port = 0;
    if (peer.ss_family == AF_INET) {
      peer_port = ntohs(reinterpret_cast<const sockaddr_in*>(&peer)->sin_port);
    } else if (peer.ss_family == AF_INET6) {
      peer_port = ntohs(reinterpret_cast<const sockaddr_in6*>(&peer)->sin6_port);
    }
    admit(fd, peerAddress(address), peer_port, options_.allow.allows(address));
  }
}

void RobotServer::admit(int fd, const std::string& peer, uint16_t peer_port, bool allowed) {
  if (!allowed) {
    sendAll(fd, errorLine(ProtocolErrc::kNotAllowed,
                          "address " + peer + " is not allowed on this port"));
    ::close(fd);
    if (refused_logged_.size() < kMaxRefusedLogged && refused_logged_.insert(peer).second) {
      logWarning("robot port: refused ", peer, " (not in the allow-list ",
                 options_.allow.describe(), "; logged once per address)");
    }
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  size_t& from_peer = per_address_[peer];
  std::string refusal;
  if (active_ >= options_.max_connections) {
    refusal = "too many connections (limit " + std::to_string(options_.max_connections) + ")";
  } else if (options_.max_per_address > 0 && from_peer >= options_.max_per_address) {
    refusal = "too many connections from " + peer + " (limit " +
              std::to_string(options_.max_per_address) + " per address)";
  }
  if (!refusal.empty()) {
    if (from_peer == 0) per_address_.erase(peer);
    sendAll(fd, errorLine(ProtocolErrc::kTooManyConnections, refusal));
    ::close(fd);
    return;
  }
  ++from_peer;
  connections_.emplace_back();
  Connection& c = connections_.back();
  c.fd = fd;
  c.peer = peer;
  c.peer_port = peer_port;
  ++active_;
  c.thread = std::thread([this, &c] { serve(c); });
}

void RobotServer::serve(Connection& connection) {
  const int fd = connection.fd;
  LineFramer framer(options_.max_line);
  const std::string too_long =
      errorLine(ProtocolErrc::kRequestTooLong,
                "request too long (limit " + std::to_string(options_.max_line) + " bytes)");
  using Clock = std::chrono::steady_clock;
  // Only a complete request (or an over-long one) counts as activity.
  Clock::time_point last_request = Clock::now();
  Session session;
  session.client =
      options_.label + " " + connection.peer + ":" + std::to_string(connection.peer_port);
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
  const auto idle = options_.idle_timeout;
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
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = per_address_.find(connection.peer);
    if (it != per_address_.end() && --it->second == 0) per_address_.erase(it);
  }
  --active_;
  connection.done = true;
}

}  // namespace picksight::app
