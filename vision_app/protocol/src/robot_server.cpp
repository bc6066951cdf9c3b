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
#include "picksight/protocol/command_table.hpp"
#include "picksight/protocol/line_framer.hpp"

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
}  // namespace

RobotServer::RobotServer(RobotServerOptions options, Handler handler)
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
  std::lock_guard<std::mutex> lock(mutex_);
  // Wake connection threads blocked in poll/recv.
  for (auto& c : connections_) ::shutdown(c.fd, SHUT_RDWR);
  for (auto& c : connections_) {
    if (c.thread.joinable()) c.thread.join();
    ::close(c.fd);
  }
  connections_.clear();
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
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) continue;
    int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
    if (active_ >= options_.max_connections) {
      sendAll(fd, "ERROR 13 too many connections (limit " +
                      std::to_string(options_.max_connections) + ")\n");
      ::close(fd);
      continue;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    connections_.emplace_back();
    Connection& c = connections_.back();
    c.fd = fd;
    ++active_;
    c.thread = std::thread([this, &c] { serve(c); });
  }
}

void RobotServer::serve(Connection& connection) {
  const int fd = connection.fd;
  LineFramer framer(options_.max_line);
  const std::string too_long =
      "ERROR 12 request too long (limit " + std::to_string(options_.max_line) + " bytes)\n";
  const auto on_line = [&](std::string_view line) {
    std::string reply;
    try {
      reply = handler_(line);
    } catch (const std::exception& e) {
      // A bug in a command must cost one request, not the server.
      logError("robot request '", printable(line, 80), "': ", e.what());
      reply = "ERROR 99 internal error";
    }
    return sendAll(fd, reply + "\n");
  };
  const auto on_too_long = [&] { return sendAll(fd, too_long); };
  char chunk[4096];
  while (!stop_) {
    pollfd p{fd, POLLIN, 0};
    const int r = ::poll(&p, 1, 200);
    if (r == 0) continue;
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) break;
    const ssize_t n = ::recv(fd, chunk, sizeof(chunk), 0);
    if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    if (n <= 0) break;  // closed by the client, maybe mid-request: nothing to answer
    if (!framer.feed(std::string_view(chunk, static_cast<size_t>(n)), on_line, on_too_long)) break;
  }
  --active_;
  connection.done = true;
}

}  // namespace picksight::app
