// The accept loop and request gate of picksight-web (http_gate.hpp).
#include "picksight/web/http_gate.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/ioctl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <system_error>
#include <thread>
#include <unordered_map>

#include <httplib.h>

#include "picksight/common/log.hpp"
#include "picksight/common/text.hpp"
#include "picksight/web/web_errors.hpp"

namespace picksight::web {
namespace {
using Clock = std::chrono::steady_clock;

std::string peerAddress(const sockaddr_storage& peer) {
  char text[INET6_ADDRSTRLEN] = {};
  if (peer.ss_family == AF_INET)
    ::inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(&peer)->sin_addr, text,
                sizeof(text));
  else if (peer.ss_family == AF_INET6)
    ::inet_ntop(AF_INET6, &reinterpret_cast<const sockaddr_in6*>(&peer)->sin6_addr, text,
                sizeof(text));
  return text;
}

int peerPort(const sockaddr_storage& peer) {
  if (peer.ss_family == AF_INET)
    return ntohs(reinterpret_cast<const sockaddr_in*>(&peer)->sin_port);
  if (peer.ss_family == AF_INET6)
    return ntohs(reinterpret_cast<const sockaddr_in6*>(&peer)->sin6_port);
  return 0;
}

// "address|port": a connection being served (unique among open ones).
std::string connectionKey(std::string_view address, int port) {
  // httplib's address of a link-local IPv6 peer carries "%scope".
  return std::string(address.substr(0, address.find('%'))) + "|" + std::to_string(port);
}

// A waiting connection's file may hold 1024 + the pool: the soft limit of
// a service is often 1024, the hard one far higher.
void raiseDescriptorLimit() {
  rlimit limit{};
  if (::getrlimit(RLIMIT_NOFILE, &limit) != 0) return;
  const rlim_t wanted = std::min<rlim_t>(limit.rlim_max, 65536);
  if (limit.rlim_cur >= wanted) return;
  limit.rlim_cur = wanted;
  ::setrlimit(RLIMIT_NOFILE, &limit);
}

// A short answer to a connection refused here; the caller closes it.
void answerRefusal(int fd, int status, const char* reason, const std::string& message) {
  const std::string body = "{\"error\":\"" + message + "\"}";
  const std::string response =
      "HTTP/1.1 " + std::to_string(status) + " " + reason +
      "\r\nContent-Type: application/json\r\nContent-Length: " + std::to_string(body.size()) +
      "\r\nConnection: close\r\nX-Frame-Options: DENY\r\n\r\n" + body;
  (void)::send(fd, response.data(), response.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
  ::shutdown(fd, SHUT_WR);
}

// A refused connection's client may still be sending (a body over the
// limit): what it sends is read and dropped for a while before the socket
// is closed, since closing with unread bytes resets the connection, and a
// reset makes the client lose the answer (or, unless it ignores SIGPIPE,
// its life).
constexpr auto kLinger = std::chrono::seconds(2);
constexpr size_t kLingerBytes = 1 << 20;
constexpr size_t kMaxLingering = 1024;

// What the bytes received so far say about a request.
enum class Progress { kWaiting, kComplete, kHeaderTooLarge, kBodyTooLarge, kChunked, kNotTls };

// `head`: the first bytes of the connection (peeked, not consumed);
// `available`: all the bytes received. The request is complete once its
// header's blank line and Content-Length bytes after it have arrived.
Progress requestProgress(std::string_view head, size_t available, const GateOptions& options) {
  const size_t end = head.find("\r\n\r\n");
  if (end == std::string_view::npos)
    return head.size() >= options.max_header_bytes ? Progress::kHeaderTooLarge : Progress::kWaiting;
  std::string header(head.substr(0, end + 2));
  std::transform(header.begin(), header.end(), header.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (header.find("\r\ntransfer-encoding:") != std::string::npos) return Progress::kChunked;
  size_t length = 0;
  const size_t at = header.find("\r\ncontent-length:");
  if (at != std::string::npos) {
    const char* p = header.c_str() + at + 17;
    while (*p == ' ' || *p == '\t') ++p;
    char* after = nullptr;
    const unsigned long long parsed = std::strtoull(p, &after, 10);
    // A length httplib cannot read is httplib's to refuse (400).
    if (after == p) return Progress::kComplete;
    if (parsed > options.max_body_bytes) return Progress::kBodyTooLarge;
    length = static_cast<size_t>(parsed);
  }
  return available >= end + 4 + length ? Progress::kComplete : Progress::kWaiting;
}

// TLS: the first record (5 bytes of header, then its length) has arrived.
Progress tlsProgress(std::string_view head, const GateOptions& options) {
  // A TLS connection starts with a handshake record (22); plain HTTP
  // ("GET ...") would otherwise be awaited as a record of kilobytes.
  if (!head.empty() && static_cast<unsigned char>(head[0]) != 22) return Progress::kNotTls;
  if (head.size() < 5) return Progress::kWaiting;
  const size_t length =
      (static_cast<unsigned char>(head[3]) << 8) | static_cast<unsigned char>(head[4]);
  if (length + 5 > options.max_header_bytes) return Progress::kHeaderTooLarge;
  return head.size() >= length + 5 ? Progress::kComplete : Progress::kWaiting;
}

}  // namespace

class HttpGate::Impl {
 public:
  Impl(GateOptions options, RefusalLog& refusals) : options_(options), refusals_(refusals) {}
  ~Impl() {
    stop();
    join();
    if (listen_fd_ >= 0) ::close(listen_fd_);
    if (wake_fd_ >= 0) ::close(wake_fd_);
    if (epoll_fd_ >= 0) ::close(epoll_fd_);
  }

  Result<uint16_t> listen(const std::string& host, uint16_t port);
  void start(Serve serve);
  void stop();
  void join();
  size_t waiting() const { return waiting_count_.load(); }
  void arrived(const std::string& address, int port);
  int listening() const { return listen_fd_; }

 private:
  struct Waiting {
    std::string address;
    uint64_t serial = 0;
    Clock::time_point deadline;
    int port = 0;
  };
  // TLS: a connection handed to the pool before its request could be seen
  // (encrypted), held to the same deadline: a duplicate of its socket is
  // kept, and shut down at the deadline unless arrived() said the request
  // was read; the serving thread then ends.
  struct Served {
    int watch = -1;
    Clock::time_point deadline;
    std::string address;
    bool arrived = false;
    bool cut = false;
  };
  void cutLateServed(Clock::time_point now);
  // TLS: runs `job` (a connection from its ClientHello on) on a thread of
  // its own, at most max_waiting at once; false when it did not (the pool's
  // then). A TLS connection's thread waits for its handshake and request,
  // up to header_timeout: on the pool's threads, 64 clients trickling
  // bytes after a handshake held them all and the page waited seconds.
  bool serveOnOwnThread(const std::function<void()>& job);
  void run();
  void acceptAll();
  void check(int fd);
  void expire(Clock::time_point now);
  // Takes `fd` out of the waiting set (and epoll); its address's count
  // stays until release().
  Waiting forget(int fd);
  void release(const std::string& address);
  void refuse(int fd, const std::string& address, int status, const char* reason,
              const std::string& message);
  // Keeps a refused connection open (reading and dropping) for kLinger.
  void linger(int fd);
  void drain(int fd);

  const GateOptions options_;
  RefusalLog& refusals_;
  Serve serve_;
  int listen_fd_ = -1;
  int epoll_fd_ = -1;
  int wake_fd_ = -1;
  std::thread thread_;
  std::unique_ptr<httplib::ThreadPool> pool_;
  std::mutex own_mutex_;
  std::condition_variable own_done_;
  size_t own_threads_ = 0;  // under own_mutex_: TLS connections' own threads
  std::atomic<bool> stopping_{false};
  std::atomic<size_t> waiting_count_{0};
  bool accept_paused_ = false;  // out of descriptors: the gate's thread only
  Clock::time_point accept_resume_;

  // The gate's thread only.
  std::unordered_map<int, Waiting> waiting_;
  std::deque<std::pair<Clock::time_point, std::pair<int, uint64_t>>> deadlines_;  // in order
  uint64_t next_serial_ = 0;

  struct Lingering {
    Clock::time_point deadline;
    size_t budget = 0;
  };
  std::unordered_map<int, Lingering> lingering_;
  std::deque<std::pair<Clock::time_point, int>> linger_deadlines_;  // in order

  std::mutex served_mutex_;
  std::unordered_map<std::string, Served> served_;  // under served_mutex_

  std::mutex per_address_mutex_;
  std::map<std::string, int> per_address_;  // under per_address_mutex_
};

Result<uint16_t> HttpGate::Impl::listen(const std::string& host, uint16_t port) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(port);
  const bool any = host.empty() || host == "*";
  if (int rc = ::getaddrinfo(any ? nullptr : host.c_str(), service.c_str(), &hints, &found);
      rc != 0)
    return makeError(WebErrc::kBadConfig, "cannot resolve '" + host + "': " + gai_strerror(rc));
  std::string last = "no address";
  for (addrinfo* a = found; a != nullptr && listen_fd_ < 0; a = a->ai_next) {
    const int fd =
        ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol);
    if (fd < 0) continue;
    int one = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
    if (::bind(fd, a->ai_addr, a->ai_addrlen) == 0 && ::listen(fd, SOMAXCONN) == 0) {
      listen_fd_ = fd;
      break;
    }
    last = std::strerror(errno);
    ::close(fd);
  }
  ::freeaddrinfo(found);
  if (listen_fd_ < 0)
    return makeError(WebErrc::kBadConfig, "cannot listen on " + host + ":" + service + ": " + last);
  sockaddr_storage bound{};
  socklen_t length = sizeof(bound);
  ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&bound), &length);
  const uint16_t bound_port =
      ntohs(bound.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6*>(&bound)->sin6_port
                                        : reinterpret_cast<sockaddr_in*>(&bound)->sin_port);
  return bound_port;
}

void HttpGate::Impl::start(Serve serve) {
  serve_ = std::move(serve);
  raiseDescriptorLimit();
  epoll_fd_ = ::epoll_create1(EPOLL_CLOEXEC);
  wake_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  epoll_event e{};
  e.events = EPOLLIN;
  e.data.fd = listen_fd_;
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, listen_fd_, &e);
  e.data.fd = wake_fd_;
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, wake_fd_, &e);
  pool_ = std::make_unique<httplib::ThreadPool>(options_.threads);
  thread_ = std::thread([this] { run(); });
}

void HttpGate::Impl::stop() {
  if (stopping_.exchange(true)) return;
  if (wake_fd_ >= 0) {
    const uint64_t one = 1;
    (void)!::write(wake_fd_, &one, sizeof(one));
  }
  if (thread_.joinable()) thread_.join();
}

void HttpGate::Impl::join() {
  if (pool_) pool_->shutdown();
  pool_.reset();
  std::unique_lock<std::mutex> lock(own_mutex_);
  own_done_.wait(lock, [this] { return own_threads_ == 0; });
}

void HttpGate::Impl::run() {
  epoll_event events[64];
  while (!stopping_) {
    int timeout_ms = 1000;
    const auto now = Clock::now();
    const auto until = [&](Clock::time_point t) {
      return static_cast<int>(std::clamp<int64_t>(
          std::chrono::duration_cast<std::chrono::milliseconds>(t - now).count() + 1, 0, 1000));
    };
    if (!deadlines_.empty()) timeout_ms = until(deadlines_.front().first);
    if (!linger_deadlines_.empty())
      timeout_ms = std::min(timeout_ms, until(linger_deadlines_.front().first));
    if (accept_paused_) timeout_ms = std::min(timeout_ms, 100);
    if (options_.tls) timeout_ms = std::min(timeout_ms, 100);
    const int n = ::epoll_wait(epoll_fd_, events, 64, timeout_ms);
    if (stopping_) break;
    for (int i = 0; i < n; ++i) {
      const int fd = events[i].data.fd;
      if (fd == wake_fd_) continue;
      if (fd == listen_fd_)
        acceptAll();
      else if (lingering_.count(fd) > 0)
        drain(fd);
      else
        check(fd);
    }
    expire(Clock::now());
    if (options_.tls) cutLateServed(Clock::now());
    if (accept_paused_ && Clock::now() >= accept_resume_) {
      accept_paused_ = false;
      epoll_event e{};
      e.events = EPOLLIN;
      e.data.fd = listen_fd_;
      ::epoll_ctl(epoll_fd_, EPOLL_CTL_MOD, listen_fd_, &e);
    }
  }
  for (auto& [fd, w] : waiting_) {
    ::close(fd);
    release(w.address);
  }
  for (auto& [fd, l] : lingering_) ::close(fd);
  lingering_.clear();
  waiting_.clear();
  waiting_count_ = 0;
}

void HttpGate::Impl::acceptAll() {
  while (!stopping_) {
    sockaddr_storage peer{};
    socklen_t length = sizeof(peer);
    const int fd = ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&peer), &length, SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
        // Out of descriptors: stop listening for a moment instead of being
        // woken for the same connection again and again.
        logWarning("HTTP accept: ", std::strerror(errno), "; pausing 100 ms");
        accept_paused_ = true;
        accept_resume_ = Clock::now() + std::chrono::milliseconds(100);
        epoll_event e{};
        e.events = 0;
        e.data.fd = listen_fd_;
        ::epoll_ctl(epoll_fd_, EPOLL_CTL_MOD, listen_fd_, &e);
      }
      return;  // EAGAIN: all taken; anything else: next time
    }
    const std::string address = peerAddress(peer);
    {
      std::lock_guard<std::mutex> lock(per_address_mutex_);
      int& count = per_address_[address];
      if (count >= options_.per_address) {
        refusals_.refused(address, "more than " + std::to_string(options_.per_address) +
                                       " connections from one address (--per-address)");
        answerRefusal(fd, 503, "Service Unavailable",
                      "too many connections from " + address + " (--per-address)");
        linger(fd);
        continue;
      }
      ++count;
    }
    if (waiting_.size() >= static_cast<size_t>(options_.max_waiting)) {
      refuse(fd, address, 503, "Service Unavailable",
             "too many connections waiting for their request");
      continue;
    }
    const auto deadline = Clock::now() + options_.header_timeout;
    const uint64_t serial = ++next_serial_;
    waiting_[fd] = Waiting{address, serial, deadline, peerPort(peer)};
    waiting_count_ = waiting_.size();
    deadlines_.push_back({deadline, {fd, serial}});
    // Edge-triggered: woken at each arrival of bytes, which stay in the
    // socket (peeked) for httplib to read.
    epoll_event e{};
    e.events = EPOLLIN | EPOLLRDHUP | EPOLLET;
    e.data.fd = fd;
    ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd, &e);
    check(fd);  // bytes may have come with the connection
  }
}

void HttpGate::Impl::check(int fd) {
  auto it = waiting_.find(fd);
  if (it == waiting_.end()) return;
  int available = 0;
  if (::ioctl(fd, FIONREAD, &available) != 0) available = 0;
  std::string head(std::min(options_.max_header_bytes, static_cast<size_t>(available)), '\0');
  ssize_t n = head.empty() ? 0 : ::recv(fd, head.data(), head.size(), MSG_PEEK | MSG_DONTWAIT);
  if (available == 0) {
    // Nothing to read: either not yet, or the peer has gone.
    char probe;
    n = ::recv(fd, &probe, 1, MSG_PEEK | MSG_DONTWAIT);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
      const Waiting w = forget(fd);
      ::close(fd);
      release(w.address);
    }
    return;
  }
  head.resize(n > 0 ? static_cast<size_t>(n) : 0);
  const Progress progress = options_.tls
                                ? tlsProgress(head, options_)
                                : requestProgress(head, static_cast<size_t>(available), options_);
  switch (progress) {
    case Progress::kWaiting:
      return;
    case Progress::kHeaderTooLarge: {
      const Waiting w = forget(fd);
      return refuse(fd, w.address, 431, "Request Header Fields Too Large",
                    "request header over " + std::to_string(options_.max_header_bytes) + " bytes");
    }
    case Progress::kBodyTooLarge: {
      const Waiting w = forget(fd);
      return refuse(fd, w.address, 413, "Payload Too Large",
                    "request body over " + std::to_string(options_.max_body_bytes) + " bytes");
    }
    case Progress::kChunked: {
      const Waiting w = forget(fd);
      return refuse(fd, w.address, 411, "Length Required",
                    "a request body must be sent with Content-Length");
    }
    case Progress::kNotTls: {
      const Waiting w = forget(fd);
      return refuse(fd, w.address, 400, "Bad Request",
                    "this port speaks HTTPS: use an https:// address");
    }
    case Progress::kComplete:
      break;
  }
  const Waiting w = forget(fd);
  int watch = -1;
  std::string key;
  if (options_.tls) {
    key = connectionKey(w.address, w.port);
    watch = ::fcntl(fd, F_DUPFD_CLOEXEC, 0);
    if (watch >= 0) {
      std::lock_guard<std::mutex> lock(served_mutex_);
      served_[key] = Served{watch, w.deadline, w.address};
    }
  }
  auto job = [this, fd, address = w.address, watch, key] {
    serve_(fd);
    if (watch >= 0) {
      {
        std::lock_guard<std::mutex> lock(served_mutex_);
        served_.erase(key);
      }
      ::close(watch);  // after the erase: the gate's thread never uses a closed one
    }
    release(address);
  };
  if (options_.tls && serveOnOwnThread(job)) return;
  pool_->enqueue(std::move(job));
}

bool HttpGate::Impl::serveOnOwnThread(const std::function<void()>& job) {
  {
    std::lock_guard<std::mutex> lock(own_mutex_);
    if (own_threads_ >= static_cast<size_t>(options_.max_waiting)) return false;
    ++own_threads_;
  }
  const auto done = [this] {
    std::lock_guard<std::mutex> lock(own_mutex_);
    if (--own_threads_ == 0) own_done_.notify_all();
  };
  try {
    std::thread([job, done] {
      job();
      done();
    }).detach();
    return true;
  } catch (const std::system_error&) {  // no thread to be had: the pool's
    done();
    return false;
  }
}

HttpGate::Impl::Waiting HttpGate::Impl::forget(int fd) {
  auto it = waiting_.find(fd);
  Waiting w = std::move(it->second);
  waiting_.erase(it);
  waiting_count_ = waiting_.size();
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, fd, nullptr);
  return w;
}

void HttpGate::Impl::expire(Clock::time_point now) {
  while (!deadlines_.empty() && deadlines_.front().first <= now) {
    const auto [fd, serial] = deadlines_.front().second;
    deadlines_.pop_front();
    auto it = waiting_.find(fd);
    if (it == waiting_.end() || it->second.serial != serial) continue;  // served or gone
    const Waiting w = forget(fd);
    refuse(fd, w.address, 408, "Request Timeout",
           "no complete request within " +
               formatFixed(static_cast<double>(options_.header_timeout.count()) / 1000.0, 1) +
               " s of connecting (--header-timeout)");
  }
  while (!linger_deadlines_.empty() && linger_deadlines_.front().first <= now) {
    const int fd = linger_deadlines_.front().second;
    linger_deadlines_.pop_front();
    auto it = lingering_.find(fd);
    if (it == lingering_.end() || it->second.deadline > now) continue;  // closed, or reused
    ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, fd, nullptr);
    ::close(fd);
    lingering_.erase(it);
  }
  // Served and closed connections leave their entries behind: dropped
  // from the front as they come due, so the queue holds at most one entry
  // per connection accepted within the last header_timeout.
}

void HttpGate::Impl::arrived(const std::string& address, int port) {
  std::lock_guard<std::mutex> lock(served_mutex_);
  auto it = served_.find(connectionKey(address, port));
  if (it != served_.end()) it->second.arrived = true;
}

void HttpGate::Impl::cutLateServed(Clock::time_point now) {
  std::lock_guard<std::mutex> lock(served_mutex_);
  for (auto& [key, s] : served_) {
    if (s.arrived || s.cut || s.deadline > now) continue;
    // Both ways: the serving thread's read (handshake or request) ends.
    ::shutdown(s.watch, SHUT_RDWR);
    s.cut = true;
    refusals_.refused(
        s.address,
        "no complete TLS handshake and request within " +
            formatFixed(static_cast<double>(options_.header_timeout.count()) / 1000.0, 1) +
            " s of connecting (--header-timeout)");
  }
}

void HttpGate::Impl::release(const std::string& address) {
  std::lock_guard<std::mutex> lock(per_address_mutex_);
  auto it = per_address_.find(address);
  if (it != per_address_.end() && --it->second <= 0) per_address_.erase(it);
}

void HttpGate::Impl::refuse(int fd, const std::string& address, int status, const char* reason,
                            const std::string& message) {
  refusals_.refused(address, message);
  answerRefusal(fd, status, reason, message);
  release(address);
  linger(fd);
}

void HttpGate::Impl::linger(int fd) {
  if (lingering_.size() >= kMaxLingering) {
    ::close(fd);
    return;
  }
  const auto deadline = Clock::now() + kLinger;
  lingering_[fd] = Lingering{deadline, kLingerBytes};
  linger_deadlines_.push_back({deadline, fd});
  epoll_event e{};
  e.events = EPOLLIN | EPOLLRDHUP;
  e.data.fd = fd;
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_ADD, fd, &e);
  drain(fd);
}

void HttpGate::Impl::drain(int fd) {
  auto it = lingering_.find(fd);
  if (it == lingering_.end()) return;
  char chunk[16384];
  while (true) {
    const ssize_t n = ::recv(fd, chunk, sizeof(chunk), MSG_DONTWAIT);
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return;  // more may come
    if (n < 0 && errno == EINTR) continue;
    if (n > 0 && static_cast<size_t>(n) < it->second.budget) {
      it->second.budget -= static_cast<size_t>(n);
      continue;
    }
    break;  // closed by the client, failed or over budget
  }
  ::epoll_ctl(epoll_fd_, EPOLL_CTL_DEL, fd, nullptr);
  ::close(fd);
  lingering_.erase(it);
}

HttpGate::HttpGate(GateOptions options, RefusalLog& refusals)
    : impl_(std::make_unique<Impl>(options, refusals)) {}
HttpGate::~HttpGate() = default;
Result<uint16_t> HttpGate::listen(const std::string& host, uint16_t port) {
  return impl_->listen(host, port);
}
int HttpGate::listeningSocket() const { return impl_->listening(); }
void HttpGate::start(Serve serve) { impl_->start(std::move(serve)); }
void HttpGate::stop() { impl_->stop(); }
void HttpGate::join() { impl_->join(); }
size_t HttpGate::waiting() const { return impl_->waiting(); }
void HttpGate::arrived(const std::string& address, int port) { impl_->arrived(address, port); }

}  // namespace picksight::web
