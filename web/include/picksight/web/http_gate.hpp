// The web server's listening socket, in front of cpp-httplib: connections
// wait here, on one epoll thread and without a server thread, until their
// whole request (header and body) has arrived, then go to a thread of the
// pool. cpp-httplib alone gives each connection a thread at once and
// restarts its read timeout at every byte, so 66 sockets sending a byte every
// 5 s held all its threads (issue 32). Here a request must be complete
// within header_timeout of the connection (a deadline that no byte moves),
// one address may hold per_address connections at once (waiting or
// served), and waiting ones cost a socket and no thread.
//
// Threading: listen() and start() and stop() from the owner's thread; the
// gate's thread accepts and watches the waiting connections; `serve` runs on
// the pool's threads, one call per complete request.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "picksight/common/result.hpp"
#include "picksight/web/refusal_log.hpp"

namespace picksight::web {

struct GateOptions {
  // From accept to the last byte of the request (header and body).
  std::chrono::milliseconds header_timeout{10000};
  // Connections open at once from one address, waiting or served.
  int per_address = 32;
  // Connections waiting for their request, from everyone.
  int max_waiting = 1024;
  size_t max_header_bytes = 16 * 1024;
  size_t max_body_bytes = 64 * 1024;
  // The pool's threads (streams hold one each for as long as they last).
  size_t threads = 64;
  // TLS: the bytes are encrypted, so only the first record (the
  // ClientHello) is awaited here; the handshake and the request are then
  // read by the serving thread, held to the same deadline: the gate shuts
  // the socket down at header_timeout unless arrived() was called for it.
  // That thread is the connection's own (up to max_waiting at once), not
  // one of the pool's, which slow TLS clients would otherwise all hold.
  // Anything but a TLS handshake record first is refused at once (400).
  bool tls = false;
};

class HttpGate {
 public:
  // `serve(fd)` answers the request waiting on `fd` (and closes it).
  using Serve = std::function<void(int fd)>;
  HttpGate(GateOptions options, RefusalLog& refusals);
  ~HttpGate();  // stops
  HttpGate(const HttpGate&) = delete;
  HttpGate& operator=(const HttpGate&) = delete;

  // Binds and listens on host:port (0: any free port); the bound port.
  Result<uint16_t> listen(const std::string& host, uint16_t port);
  int listeningSocket() const;
  void start(Serve serve);
  // Stops accepting and closes the waiting connections; serving ones go on
  // until join() (their streams must be told to end by the owner).
  void stop();
  // Waits for the requests being served to end.
  void join();

  // Connections waiting for their request now (for tests and /metrics).
  size_t waiting() const;
  // TLS: the request of the connection from address:port has been read
  // whole; the header deadline no longer applies to it. Any thread.
  void arrived(const std::string& address, int port);

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace picksight::web
