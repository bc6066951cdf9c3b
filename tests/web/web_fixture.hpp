// picksight-web started as a process on a free port, an HTTP client to it,
// and the polling helpers the web tests share.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <httplib.h>
#include <catch2/catch.hpp>

#include "cell_fixture.hpp"
#include "picksight/common/text.hpp"
#include "picksight/tool_support/subprocess.hpp"

namespace picksight::webtest {

struct WebProcess {
  // Starts picksight-web on 127.0.0.1 port 0 with `args`; REQUIREs its URL line.
  explicit WebProcess(std::vector<std::string> args) {
    std::vector<std::string> argv = {e2e::binPath("picksight-web"), "--listen", "127.0.0.1:0"};
    argv.insert(argv.end(), args.begin(), args.end());
    process = std::make_unique<Subprocess>(argv);
    auto url = process->waitForLine("web http://127.0.0.1:", std::chrono::seconds(10));
    REQUIRE(url);
    auto p = parseInt(*url);
    REQUIRE(p);
    port = static_cast<int>(*p);
  }
  httplib::Client client() const {
    httplib::Client c("127.0.0.1", port);
    c.set_connection_timeout(std::chrono::seconds(5));
    c.set_read_timeout(std::chrono::seconds(10));
    return c;
  }
  std::unique_ptr<Subprocess> process;
  int port = 0;
};

// Calls `done` until it returns true or `timeout` passes; its last answer.
inline bool pollUntil(const std::function<bool()>& done,
                      std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return done();
}

// The "--video-server" argument of a started video server.
inline std::vector<std::string> videoServerArgs(const e2e::VideoServerProcess& server) {
  return {"--video-server", server.frames + "," + server.control};
}

}  // namespace picksight::webtest
