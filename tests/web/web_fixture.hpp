// picksight-web started as a process on a free port, an HTTP client to it,
// and the polling helpers the web tests share.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <httplib.h>
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "cell_fixture.hpp"
#include "picksight/common/text.hpp"
#include "picksight/tool_support/subprocess.hpp"

namespace picksight::webtest {

struct WebProcess {
  // Starts picksight-web on 127.0.0.1 port 0 with `args`; REQUIREs its URL
  // line. With --tls-cert among `args`, `ca_cert` is the certificate the
  // clients verify the server's against.
  explicit WebProcess(std::vector<std::string> args, std::string ca_cert = "")
      : ca(std::move(ca_cert)) {
    std::vector<std::string> argv = {e2e::binPath("picksight-web"), "--listen", "127.0.0.1:0"};
    argv.insert(argv.end(), args.begin(), args.end());
    process = std::make_unique<tool_support::Subprocess>(argv);
    // With no users yet the server makes 'admin' and prints its password
    // once, before its URL; the tests log in with it.
    std::string url_prefix = "web http://127.0.0.1:";
    std::optional<std::string> line;
    while ((line = process->readLine(std::chrono::seconds(10)))) {
      if (line->rfind("admin-password ", 0) == 0) admin_password = line->substr(15);
      if (line->rfind("redirect ", 0) == 0) redirect_url = line->substr(9);
      if (line->rfind("web https://", 0) == 0) {
        https = true;
        url_prefix = "web https://127.0.0.1:";
      }
      if (line->rfind(url_prefix, 0) == 0) break;
    }
    REQUIRE(line);
    auto p = parseInt(line->substr(url_prefix.size()));
    REQUIRE(p);
    port = static_cast<int>(*p);
    if (!admin_password.empty()) cookie = login("admin", admin_password);
  }
  // A client logged in as the admin (when the server printed its password).
  httplib::Client client() const {
    httplib::Client c = anonymousClient();
    if (!cookie.empty()) c.set_default_headers({{"Cookie", cookie}});
    return c;
  }
  httplib::Client anonymousClient() const {
    httplib::Client c((https ? "https://127.0.0.1:" : "http://127.0.0.1:") + std::to_string(port));
    if (https) {
      c.set_ca_cert_path(ca.c_str());
      c.enable_server_certificate_verification(true);
    }
    c.set_connection_timeout(std::chrono::seconds(5));
    c.set_read_timeout(std::chrono::seconds(10));
    return c;
  }
  // A client that sends `cookie` (a session from login()).
  httplib::Client as(const std::string& cookie) const {
    httplib::Client c = anonymousClient();
    c.set_default_headers({{"Cookie", cookie}});
    return c;
  }
  // POST /api/login; the session's "name=value" for a Cookie header, empty
  // when refused.
  std::string login(const std::string& user, const std::string& password) const {
    auto res = anonymousClient().Post(
        "/api/login", {{"X-PickSight", "1"}},
        "{\"user\":\"" + user + "\",\"password\":\"" + password + "\"}", "application/json");
    if (!res || res->status != 200) return "";
    const std::string set = res->get_header_value("Set-Cookie");
    return set.substr(0, set.find(';'));
  }
  // "Cookie: ...\r\n" for a raw request, logged in as the admin.
  std::string cookieLine() const { return cookie.empty() ? "" : "Cookie: " + cookie + "\r\n"; }
  std::string ca;
  std::unique_ptr<tool_support::Subprocess> process;
  int port = 0;
  bool https = false;
  std::string redirect_url;  // "http://127.0.0.1:PORT" with --http-redirect
  std::string admin_password;
  std::string cookie;
};

// A POST as the page sends it: JSON with the X-PickSight header.
inline httplib::Result postJson(httplib::Client& client, const std::string& path,
                                const nlohmann::json& body) {
  return client.Post(path.c_str(), {{"X-PickSight", "1"}}, body.dump(), "application/json");
}

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
