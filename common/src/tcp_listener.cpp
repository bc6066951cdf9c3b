// TCP listener: the listening socket, accept, and the admission counts
// shared with the connections that hold a slot.
#include "picksight/common/tcp_listener.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>

#include "picksight/common/log.hpp"

namespace picksight {
namespace {
// The kernel's queue of completed connections not yet accepted; admission
// decides after accept, so a short queue would only refuse silently.
constexpr int kBacklog = 64;

// Addresses whose refusals are counted one by one; beyond this many (a scan
// of the network) the rest share one count.
constexpr size_t kMaxRefusedAddresses = 1024;

timeval toTimeval(std::chrono::milliseconds ms) {
  timeval tv{};
  tv.tv_sec = static_cast<time_t>(ms.count() / 1000);
  tv.tv_usec = static_cast<suseconds_t>((ms.count() % 1000) * 1000);
  return tv;
}

uint16_t portOf(const sockaddr_storage& peer) {
  if (peer.ss_family == AF_INET)
    return ntohs(reinterpret_cast<const sockaddr_in*>(&peer)->sin_port);
  if (peer.ss_family == AF_INET6)
    return ntohs(reinterpret_cast<const sockaddr_in6*>(&peer)->sin6_port);
  return 0;
}
}  // namespace

struct TcpListener::Connection::Admission {
  std::mutex mutex;  // guards every field
  size_t open = 0;
  std::map<std::string, size_t> per_address;  // open connections by peer address
  std::map<std::string, uint64_t> refused;    // refusals by address, bounded
  uint64_t refused_untracked = 0;             // from addresses beyond the bound
  uint64_t refusals = 0;
};

Socket& Socket::operator=(Socket&& other) noexcept {
  if (this != &other) {
    reset();
    fd_ = other.release();
  }
  return *this;
}

void Socket::reset() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

bool sendAll(int fd, std::string_view data) {
  size_t sent = 0;
  while (sent < data.size()) {
    const ssize_t n = ::send(fd, data.data() + sent, data.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    sent += static_cast<size_t>(n);
  }
  return true;
}

bool refusalLogged(uint64_t count) {
  while (count >= 10 && count % 10 == 0) count /= 10;
  return count == 1;
}

TcpListener::Connection& TcpListener::Connection::operator=(Connection&& other) noexcept {
  if (this != &other) {
    releaseSlot();
    socket_ = std::move(other.socket_);
    peer_address_ = std::move(other.peer_address_);
    peer_port_ = other.peer_port_;
    admission_ = std::move(other.admission_);
  }
  return *this;
}

void TcpListener::Connection::releaseSlot() {
  if (!admission_) return;
  std::lock_guard<std::mutex> lock(admission_->mutex);
  --admission_->open;
  auto it = admission_->per_address.find(peer_address_);
  if (it != admission_->per_address.end() && --it->second == 0) admission_->per_address.erase(it);
  admission_.reset();
}

TcpListener::TcpListener(std::string name, TcpListenerOptions options, RefusalReply reply,
                         RefusalLog log)
    : name_(std::move(name)),
      options_(std::move(options)),
      reply_(std::move(reply)),
      log_(log ? std::move(log) : RefusalLog([](const std::string& line) { logWarning(line); })),
      admission_(std::make_shared<Connection::Admission>()) {
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(options_.port);
  if (::inet_pton(AF_INET, options_.bind_address.c_str(), &addr.sin_addr) != 1)
    throw std::runtime_error(name_ + ": bad bind address '" + options_.bind_address + "'");
  socket_ = Socket(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
  if (!socket_.valid()) throw std::runtime_error(name_ + ": socket: " + std::strerror(errno));
  int one = 1;
  ::setsockopt(socket_.fd(), SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  if (::bind(socket_.fd(), reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0 ||
      ::listen(socket_.fd(), kBacklog) != 0) {
    throw std::runtime_error(name_ + ": cannot listen on " + options_.bind_address + ":" +
                             std::to_string(options_.port) + ": " + std::strerror(errno));
  }
  socklen_t len = sizeof(addr);
  ::getsockname(socket_.fd(), reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
}

TcpListener::~TcpListener() = default;

std::optional<TcpListener::Connection> TcpListener::accept() {
  sockaddr_storage peer{};
  socklen_t peer_len = sizeof(peer);
  Socket socket(
      ::accept4(socket_.fd(), reinterpret_cast<sockaddr*>(&peer), &peer_len, SOCK_CLOEXEC));
  if (!socket.valid()) return std::nullopt;
  // Before any reply, refusals included: a peer that does not read must not
  // hold the accepting thread.
  const timeval send_timeout = toTimeval(options_.send_timeout);
  ::setsockopt(socket.fd(), SOL_SOCKET, SO_SNDTIMEO, &send_timeout, sizeof(send_timeout));
  int one = 1;
  ::setsockopt(socket.fd(), IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  const auto* who = reinterpret_cast<const sockaddr*>(&peer);
  const std::string address = picksight::peerAddress(who);
  if (!options_.allow.allows(who)) {
    refuse(std::move(socket), address, Refusal::kNotAllowed,
           "address " + address + " is not allowed on this port");
    return std::nullopt;
  }
  std::unique_lock<std::mutex> lock(admission_->mutex);
  if (admission_->open >= options_.max_connections) {
    lock.unlock();
    refuse(std::move(socket), address, Refusal::kTooMany,
           "too many connections (limit " + std::to_string(options_.max_connections) + ")");
    return std::nullopt;
  }
  size_t& from_peer = admission_->per_address[address];
  if (options_.max_per_address > 0 && from_peer >= options_.max_per_address) {
    lock.unlock();
    refuse(std::move(socket), address, Refusal::kTooManyFromAddress,
           "too many connections from " + address + " (limit " +
               std::to_string(options_.max_per_address) + " per address)");
    return std::nullopt;
  }
  ++from_peer;
  ++admission_->open;
  return Connection(std::move(socket), address, portOf(peer), admission_);
}

void TcpListener::refuse(Socket socket, const std::string& address, Refusal why,
                         const std::string& text) {
  if (reply_) sendAll(socket.fd(), reply_(why, text));
  socket.reset();
  uint64_t count = 0;
  bool tracked = true;
  {
    std::lock_guard<std::mutex> lock(admission_->mutex);
    ++admission_->refusals;
    auto it = admission_->refused.find(address);
    if (it == admission_->refused.end() && admission_->refused.size() < kMaxRefusedAddresses)
      it = admission_->refused.emplace(address, 0).first;
    if (it != admission_->refused.end()) {
      count = ++it->second;
    } else {
      tracked = false;
      count = ++admission_->refused_untracked;
    }
  }
  if (!refusalLogged(count)) return;
  std::string line = name_ + ": refused " + address + " (" + text;
  if (why == Refusal::kNotAllowed) line += "; allow-list " + options_.allow.describe();
  line += "); ";
  if (!tracked) {
    line += std::to_string(count) + " refusals from addresses beyond the " +
            std::to_string(kMaxRefusedAddresses) + " counted one by one";
  } else {
    line += count == 1 ? std::string("first refusal") : std::to_string(count) + " refusals";
    line += " of this address, logged at the 1st, 10th, 100th...";
  }
  log_(line);
}

size_t TcpListener::connections() const {
  std::lock_guard<std::mutex> lock(admission_->mutex);
  return admission_->open;
}

uint64_t TcpListener::refusals() const {
  std::lock_guard<std::mutex> lock(admission_->mutex);
  return admission_->refusals;
}

}  // namespace picksight
