// Modbus TCP server: libmodbus replies; one poll() loop frames
// the requests of every connection, with a bound on connections, on bytes
// per request and on idle time.
#include "picksight/plc/modbus_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <list>
#include <stdexcept>
#include <vector>

#include "picksight/common/log.hpp"

namespace picksight::plc {
namespace {
using Clock = std::chrono::steady_clock;

struct Connection {
  int fd = -1;
  std::vector<uint8_t> pending;  // bytes of the request being received
  Clock::time_point last_request;
};
}  // namespace

ModbusServer::ModbusServer(ModbusServerOptions options, PlcDevice& device)
    : options_(std::move(options)), device_(device) {
  // The listening socket is ours (libmodbus's listen binds every address in
  // some versions); libmodbus builds and sends the replies.
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(options_.port);
  if (::inet_pton(AF_INET, options_.bind_address.c_str(), &addr.sin_addr) != 1)
    throw std::runtime_error("Modbus server: bad bind address '" + options_.bind_address + "'");
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0)
    throw std::runtime_error(std::string("Modbus server: socket: ") + std::strerror(errno));
  int one = 1;
  ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0 ||
      ::listen(listen_fd_, 16) != 0) {
    const std::string why = std::strerror(errno);
    ::close(listen_fd_);
    throw std::runtime_error("Modbus server: cannot listen on " + options_.bind_address + ":" +
                             std::to_string(options_.port) + ": " + why);
  }
  socklen_t len = sizeof(addr);
  ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
  replier_ = modbus_new_tcp("127.0.0.1", 502);  // only its socket is ever set
  if (!replier_) {
    ::close(listen_fd_);
    throw std::runtime_error("Modbus server: out of memory");
  }
}

ModbusServer::~ModbusServer() {
  stop();
  ::close(listen_fd_);
  modbus_free(replier_);
}

void ModbusServer::start() {
  if (thread_.joinable()) return;
  stop_ = false;
  thread_ = std::thread([this] { loop(); });
}

void ModbusServer::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void ModbusServer::loop() {
  std::list<Connection> open;
  const auto close = [&](std::list<Connection>::iterator it) {
    ::close(it->fd);
    --connections_;
    return open.erase(it);
  };
  std::vector<pollfd> polled;
  uint8_t chunk[512];
  while (!stop_) {
    polled.assign(1, pollfd{listen_fd_, POLLIN, 0});
    for (const auto& c : open) polled.push_back(pollfd{c.fd, POLLIN, 0});
    const int ready = ::poll(polled.data(), polled.size(), 100);
    if (ready < 0 && errno != EINTR) {
      logError("Modbus server: poll: ", std::strerror(errno));
      break;
    }
    const auto now = Clock::now();
    // Connections first: polled[1..] are in the order of `open`.
    size_t index = 1;
    for (auto it = open.begin(); it != open.end(); ++index) {
      const short events = ready > 0 ? polled[index].revents : 0;
      if (events == 0) {
        it = now - it->last_request > options_.idle_timeout ? close(it) : std::next(it);
        continue;
      }
      const ssize_t n = ::recv(it->fd, chunk, sizeof(chunk), MSG_DONTWAIT);
      if (n < 0 && (errno == EINTR || errno == EAGAIN)) {
        ++it;
        continue;
      }
      if (n <= 0) {
        it = close(it);
        continue;
      }
      it->pending.insert(it->pending.end(), chunk, chunk + n);
      bool keep = true;
      while (keep) {
        const auto length = aduLength(it->pending.data(), it->pending.size());
        if (!length) {
          keep = false;  // not Modbus TCP: the stream cannot be followed
          break;
        }
        if (*length == 0) break;
        it->last_request = now;
        modbus_set_socket(replier_, it->fd);
        keep = device_.handle(replier_, it->pending.data(), *length);
        it->pending.erase(it->pending.begin(),
                          it->pending.begin() + static_cast<std::ptrdiff_t>(*length));
      }
      modbus_set_socket(replier_, -1);
      it = keep ? std::next(it) : close(it);
    }
    if (ready > 0 && (polled[0].revents & POLLIN)) {
      sockaddr_storage peer{};
      socklen_t len = sizeof(peer);
      const int fd = ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&peer), &len, SOCK_CLOEXEC);
      if (fd < 0) continue;
      const auto* who = reinterpret_cast<const sockaddr*>(&peer);
      if (!options_.allow.allows(who)) {
        logInfo("Modbus: refused ", peerAddress(who), " (not in --modbus-allow)");
        ::close(fd);
        continue;
      }
      if (open.size() >= options_.max_connections) {
        logInfo("Modbus: refused ", peerAddress(who), " (", options_.max_connections,
                " connections open)");
        ::close(fd);
        continue;
      }
      int one = 1;
      ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
      // A peer that stops reading costs its own connection, not the loop.
      timeval send_timeout{1, 0};
      ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &send_timeout, sizeof(send_timeout));
      open.push_back(Connection{fd, {}, now});
      ++connections_;
    }
  }
  while (!open.empty()) close(open.begin());
}

}  // namespace picksight::plc
