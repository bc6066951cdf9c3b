// One TCP listening port and who it lets in: the robot port and the Modbus
// port share it, so that both bind, accept, refuse and bound their peers the
// same way.
//
// Admission: peers outside the allow-list, beyond max_connections, or beyond
// max_per_address from one address are answered (the server says with what)
// and closed; each refusal is logged at the 1st, 10th, 100th... refusal of
// its address, with the count, so that a scan or a reconnecting PLC cannot
// flood the log. Admitted sockets get TCP_NODELAY and a send timeout, so a
// peer that stops reading costs its own connection, never a server thread.
// The idle timeout is a policy the server's read loop applies (only it knows
// what a complete request is).
//
// Threading: accept() from one thread (the server's accept or poll loop); a
// Connection may be released or destroyed from any thread, even after the
// listener is gone.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "picksight/common/allow_list.hpp"

namespace picksight {

// A socket's file descriptor, closed when its owner goes; move-only.
class Socket {
 public:
  Socket() = default;
  explicit Socket(int fd) : fd_(fd) {}
  ~Socket() { reset(); }
  Socket(Socket&& other) noexcept : fd_(other.release()) {}
  Socket& operator=(Socket&& other) noexcept;
  Socket(const Socket&) = delete;
  Socket& operator=(const Socket&) = delete;

  int fd() const { return fd_; }
  bool valid() const { return fd_ >= 0; }
  int release() {
    const int fd = fd_;
    fd_ = -1;
    return fd;
  }
  void reset();  // closes

 private:
  int fd_ = -1;
};

// Writes all of `data` (no SIGPIPE); false when the peer is gone or the
// socket's send timeout expired.
bool sendAll(int fd, std::string_view data);

struct TcpListenerOptions {
  std::string bind_address = "0.0.0.0";
  uint16_t port = 0;  // 0 = any free port (read it back with port())
  AllowList allow;    // empty: everyone
  size_t max_connections = 64;
  // From one address; half the total, so that one host (a misbehaving
  // gateway, a scan) leaves room for the others. 0 = no limit of its own.
  size_t max_per_address = 32;
  // No complete request for this long: the server closes the connection.
  // 0 = never.
  std::chrono::milliseconds idle_timeout{60000};
  // A send that makes no progress for this long fails (SO_SNDTIMEO).
  std::chrono::milliseconds send_timeout{1000};
};

class TcpListener {
 public:
  // Why a peer was refused.
  enum class Refusal { kNotAllowed, kTooMany, kTooManyFromAddress };
  // The bytes sent to a refused peer before it is closed ("" = none), from
  // the refusal and its text ("too many connections (limit 64)").
  using RefusalReply = std::function<std::string(Refusal, const std::string& why)>;
  // Where refusal lines go (a warning in the log unless a test says else).
  using RefusalLog = std::function<void(const std::string& line)>;

  // An admitted peer. It holds one of the listener's connection slots until
  // releaseSlot() or its destruction; the socket closes with it.
  class Connection {
   public:
    Connection(Connection&&) noexcept = default;
    Connection& operator=(Connection&& other) noexcept;  // releases this one's slot first
    ~Connection() { releaseSlot(); }

    int fd() const { return socket_.fd(); }
    const std::string& peerAddress() const { return peer_address_; }
    uint16_t peerPort() const { return peer_port_; }
    // Frees the slot while the socket stays open (a server that closes its
    // sockets later, after joining the thread that used them). Idempotent.
    void releaseSlot();

   private:
    friend class TcpListener;
    struct Admission;
    Connection(Socket socket, std::string address, uint16_t port,
               std::shared_ptr<Admission> admission)
        : socket_(std::move(socket)),
          peer_address_(std::move(address)),
          peer_port_(port),
          admission_(std::move(admission)) {}

    Socket socket_;
    std::string peer_address_;
    uint16_t peer_port_ = 0;
    std::shared_ptr<Admission> admission_;  // null once the slot is released
  };

  // Binds and listens at once; throws std::runtime_error naming `name`
  // ("robot port") and the port. The listening socket does not block.
  TcpListener(std::string name, TcpListenerOptions options, RefusalReply reply = {},
              RefusalLog log = {});
  ~TcpListener();
  TcpListener(const TcpListener&) = delete;
  TcpListener& operator=(const TcpListener&) = delete;

  int fd() const { return socket_.fd(); }  // to poll for a waiting peer
  uint16_t port() const { return port_; }
  const TcpListenerOptions& options() const { return options_; }

  // Takes one waiting peer, if any: the admitted connection, or nothing
  // when none waits or the peer was refused (answered, logged, closed).
  std::optional<Connection> accept();

  size_t connections() const;
  uint64_t refusals() const;  // since start, of every kind

 private:
  void refuse(Socket socket, const std::string& address, Refusal why, const std::string& text);

  const std::string name_;
  const TcpListenerOptions options_;
  const RefusalReply reply_;
  const RefusalLog log_;
  Socket socket_;
  uint16_t port_ = 0;
  std::shared_ptr<Connection::Admission> admission_;
};

// The count at which the n-th refusal of one address is logged again:
// 1, 10, 100, ... (so a million refusals cost seven lines).
bool refusalLogged(uint64_t count);

}  // namespace picksight
