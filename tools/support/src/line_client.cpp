// Robot-protocol line client over a plain TCP socket.
#include "picksight/tool_support/line_client.hpp"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "line_buffer.hpp"
#include "picksight/common/allow_list.hpp"

namespace picksight::tool_support {

LineClient::~LineClient() { close(); }

LineClient::LineClient(LineClient&& other) noexcept
    : fd_(other.fd_), buffer_(std::move(other.buffer_)) {
  other.fd_ = -1;
}

LineClient& LineClient::operator=(LineClient&& other) noexcept {
  if (this != &other) {
    close();
    fd_ = other.fd_;
    buffer_ = std::move(other.buffer_);
    other.fd_ = -1;
  }
  return *this;
}

std::string LineClient::localEndpoint() const {
  sockaddr_storage local{};
  socklen_t length = sizeof local;
  if (fd_ < 0 || ::getsockname(fd_, reinterpret_cast<sockaddr*>(&local), &length) != 0) return "";
  const auto* address = reinterpret_cast<const sockaddr*>(&local);
  const uint16_t port = local.ss_family == AF_INET6
                            ? ntohs(reinterpret_cast<const sockaddr_in6*>(&local)->sin6_port)
                            : ntohs(reinterpret_cast<const sockaddr_in*>(&local)->sin_port);
  return peerAddress(address) + ":" + std::to_string(port);
}

void LineClient::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  buffer_.clear();
}

Result<LineClient> LineClient::connect(const std::string& host, uint16_t port,
                                       std::chrono::milliseconds timeout) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(port);
  if (int rc = ::getaddrinfo(host.c_str(), service.c_str(), &hints, &found); rc != 0) {
    return systemError(EHOSTUNREACH, "cannot resolve " + host + ": " + gai_strerror(rc));
  }
  Error last = systemError(ECONNREFUSED, "cannot connect to " + host + ":" + service);
  for (addrinfo* a = found; a != nullptr; a = a->ai_next) {
    int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol);
    if (fd < 0) continue;
    int rc = ::connect(fd, a->ai_addr, a->ai_addrlen);
    if (rc != 0 && errno == EINPROGRESS) {
      pollfd p{fd, POLLOUT, 0};
      if (::poll(&p, 1, static_cast<int>(timeout.count())) == 1) {
        int err = 0;
        socklen_t len = sizeof(err);
        ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len);
        rc = err == 0 ? 0 : -1;
        errno = err;
      } else {
        errno = ETIMEDOUT;
      }
    }
    if (rc == 0) {
      ::freeaddrinfo(found);
      int one = 1;
      ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
      return LineClient(fd);
    }
    last = systemError(errno, "cannot connect to " + host + ":" + service + ": " + strerror(errno));
    ::close(fd);
  }
  ::freeaddrinfo(found);
  return last;
}

Result<void> LineClient::sendRaw(const std::string& bytes) {
  if (fd_ < 0) return systemError(ENOTCONN, "not connected");
  size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n = ::send(fd_, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      pollfd p{fd_, POLLOUT, 0};
      ::poll(&p, 1, 1000);
      continue;
    }
    if (n <= 0) return systemError(errno, std::string("send: ") + strerror(errno));
    sent += static_cast<size_t>(n);
  }
  return {};
}

Result<std::string> LineClient::readLine(std::chrono::milliseconds timeout) {
  if (fd_ < 0) return systemError(ENOTCONN, "not connected");
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    if (auto line = takeLine(buffer_)) {
      if (!line->empty() && line->back() == '\r') line->pop_back();
      return *line;
    }
    const auto left = timeLeft(deadline);
    if (left.count() <= 0) return systemError(ETIMEDOUT, "no reply in time");
    pollfd p{fd_, POLLIN, 0};
    const int r = ::poll(&p, 1, static_cast<int>(left.count()));
    if (r < 0 && errno == EINTR) continue;
    if (r == 0) return systemError(ETIMEDOUT, "no reply in time");
    char chunk[4096];
    const ssize_t n = ::recv(fd_, chunk, sizeof(chunk), 0);
    if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    if (n == 0) return systemError(ECONNRESET, "connection closed by server");
    if (n < 0) return systemError(errno, std::string("recv: ") + strerror(errno));
    buffer_.append(chunk, static_cast<size_t>(n));
  }
}

Result<std::string> LineClient::request(const std::string& line,
                                        std::chrono::milliseconds timeout) {
  if (auto sent = sendRaw(line + "\n"); !sent) return sent.error();
  return readLine(timeout);
}

}  // namespace picksight::tool_support
