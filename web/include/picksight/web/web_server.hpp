// picksight-web's HTTP server (docs/WEB.md): the page, the cameras' images
// and streams, the results as Server-Sent Events, /metrics, and the JSON
// actions that go to the video servers' control sockets and the vision
// apps' robot ports.
//
// Threading: HTTP requests run on a pool of threads larger than the stream
// limit (options.max_streams), so streams never starve the page; every
// stream waits on its own camera feed or event queue and writes only from
// its own thread, with a bounded write timeout. The camera poller and the
// feeds have threads of their own (camera_monitor.hpp, camera_feed.hpp,
// result_feed.hpp). start() and stop() are for the owner's thread.
#pragma once

#include <memory>
#include <string>

#include "picksight/common/result.hpp"
#include "picksight/web/web_options.hpp"

namespace picksight::web {

class WebServer {
 public:
  explicit WebServer(WebOptions options);
  ~WebServer();  // stops
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  // Binds the listen address, starts the feeds and serves on a thread.
  Result<void> start();
  // The bound port, and "http://HOST:PORT" ("https://" with TLS).
  uint16_t port() const;
  std::string url() const;
  // "http://HOST:PORT" of --http-redirect; empty without.
  std::string redirectUrl() const;
  void stop();

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace picksight::web
