// Robot TCP server framing and robustness, over real sockets.
#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <future>
#include <string>
#include <thread>
#include <vector>

#include "picksight/common/allow_list.hpp"

#include "picksight/protocol/robot_server.hpp"
#include "picksight/tool_support/line_client.hpp"

using namespace picksight;
using namespace picksight::tool_support;
using namespace std::chrono_literals;

namespace {
// Echoes the request's length and text so framing mistakes show.
std::string echo(std::string_view line) {
  return "OK " + std::to_string(line.size()) + " " + std::string(line.substr(0, 32));
}

protocol::RobotServerOptions loopback() {
  protocol::RobotServerOptions o;
  o.listen.bind_address = "127.0.0.1";
  o.listen.port = 0;
  return o;
}

struct Server {
  explicit Server(size_t max_connections = 64) {
    protocol::RobotServerOptions o = loopback();
    o.listen.max_connections = max_connections;
    start(o);
  }
  explicit Server(const protocol::RobotServerOptions& o) { start(o); }
  void start(const protocol::RobotServerOptions& o) {
    server = std::make_unique<protocol::RobotServer>(o, echo);
    server->start();
  }
  LineClient connect() {
    auto c = LineClient::connect("127.0.0.1", server->port(), 2s);
    REQUIRE(c);
    return std::move(*c);
  }
  std::unique_ptr<protocol::RobotServer> server;
};

// Two connections served and kept in `held`, then the first line a third gets.
std::string beyondTwo(Server& s, std::vector<LineClient>& held) {
  for (int i = 0; i < 2; ++i) {
    held.push_back(s.connect());
    CHECK(*held.back().request("PING", 2s) == "OK 4 PING");
  }
  auto third = s.connect();
  const auto reply = third.readLine(2s);
  REQUIRE(reply);
  return *reply;
}
}  // namespace

TEST_CASE("one reply per line, LF or CR LF, pipelined or split across writes",
          "[vision_app][robot_server]") {
  Server s;
  auto c = s.connect();
  CHECK(*c.request("PING", 2s) == "OK 4 PING");
  REQUIRE(c.sendRaw("A\r\nBB\nCC"));
  CHECK(*c.readLine(2s) == "OK 1 A");
  CHECK(*c.readLine(2s) == "OK 2 BB");
  std::this_thread::sleep_for(50ms);
  REQUIRE(c.sendRaw("C\n"));
  CHECK(*c.readLine(2s) == "OK 3 CCC");
}

TEST_CASE("a 1 MB line gets ERROR 12 and the connection goes on", "[vision_app][robot_server]") {
  Server s;
  auto c = s.connect();
  REQUIRE(c.sendRaw(std::string(1 << 20, 'x') + "\n"));
  const auto reply = c.readLine(5s);
  REQUIRE(reply);
  CHECK(reply->rfind("ERROR 12 ", 0) == 0);
  CHECK(*c.request("PING", 2s) == "OK 4 PING");
}

TEST_CASE("binary bytes and empty lines are answered, not fatal", "[vision_app][robot_server]") {
  Server s;
  auto c = s.connect();
  REQUIRE(c.sendRaw(std::string("\x00\xff\x01\x02", 4) + "\n"));
  CHECK(*c.readLine(2s) == std::string("OK 4 \x00\xff\x01\x02", 9));
  CHECK(*c.request("", 2s) == "OK 0 ");
  CHECK(*c.request("PING", 2s) == "OK 4 PING");
}

TEST_CASE("a client that leaves mid-request costs nothing", "[vision_app][robot_server]") {
  Server s;
  {
    auto gone = s.connect();
    REQUIRE(gone.sendRaw("LOCATE 1"));  // no line end, then gone
  }
  auto c = s.connect();
  CHECK(*c.request("PING", 2s) == "OK 4 PING");
}

TEST_CASE("32 connections at once each get their own replies", "[vision_app][robot_server]") {
  Server s;
  std::atomic<int> good{0};
  std::vector<std::thread> robots;
  for (int r = 0; r < 32; ++r) {
    robots.emplace_back([&, r] {
      auto c = LineClient::connect("127.0.0.1", s.server->port(), 5s);
      if (!c) return;
      for (int i = 0; i < 50; ++i) {
        const std::string req = "R" + std::to_string(r) + "-" + std::to_string(i);
        auto reply = c->request(req, 5s);
        if (reply && *reply == "OK " + std::to_string(req.size()) + " " + req) ++good;
      }
    });
  }
  for (auto& t : robots) t.join();
  CHECK(good == 32 * 50);
}

TEST_CASE("connections beyond the limit are told why and closed", "[vision_app][robot_server]") {
  Server s(2);
  std::vector<LineClient> held;
  CHECK(beyondTwo(s, held).rfind("ERROR 13 ", 0) == 0);
  held[0].close();
  // The slot frees once the server notices the close.
  bool served = false;
  for (int i = 0; i < 50 && !served; ++i) {
    std::this_thread::sleep_for(50ms);
    auto d = LineClient::connect("127.0.0.1", s.server->port(), 2s);
    if (!d) continue;
    auto r = d->request("PING", 2s);
    served = r && *r == "OK 4 PING";
  }
  CHECK(served);
}

TEST_CASE("a peer outside the allow-list gets ERROR 15 and is closed",
          "[vision_app][robot_server]") {
  protocol::RobotServerOptions o = loopback();
  auto list = AllowList::parse("10.0.0.0/8");
  REQUIRE(list);
  o.listen.allow = *list;
  Server refusing(o);
  for (int i = 0; i < 3; ++i) {  // every time, logged once
    auto c = refusing.connect();
    const auto reply = c.readLine(2s);
    REQUIRE(reply);
    CHECK(reply->rfind("ERROR 15 address 127.0.0.1 is not allowed", 0) == 0);
    CHECK_FALSE(c.readLine(2s));  // closed
  }
  o.listen.allow = *AllowList::parse("10.0.0.0/8 127.0.0.0/8");
  Server allowing(o);
  auto c = allowing.connect();
  CHECK(*c.request("PING", 2s) == "OK 4 PING");
}

TEST_CASE("connections beyond the per-address limit are told why and closed",
          "[vision_app][robot_server]") {
  protocol::RobotServerOptions o = loopback();
  o.listen.max_per_address = 2;
  Server s(o);
  std::vector<LineClient> held;
  CHECK(beyondTwo(s, held).rfind(
            "ERROR 13 too many connections from 127.0.0.1 (limit 2 per address)", 0) == 0);
  CHECK(*held[0].request("PING", 2s) == "OK 4 PING");
}

TEST_CASE("an idle or trickling connection gets ERROR 16 and is closed",
          "[vision_app][robot_server]") {
  protocol::RobotServerOptions o = loopback();
  o.listen.idle_timeout = 300ms;
  Server s(o);
  auto idle = s.connect();
  auto trickling = s.connect();
  CHECK(*trickling.request("PING", 2s) == "OK 4 PING");
  // Bytes that never end a line are no request: the connection is idle.
  for (int i = 0; i < 20 && trickling.sendRaw("x"); ++i) std::this_thread::sleep_for(50ms);
  for (auto* c : {&idle, &trickling}) {
    const auto reply = c->readLine(10s);
    REQUIRE(reply);
    CHECK(reply->rfind("ERROR 16 no request for 0.3 s", 0) == 0);
    CHECK_FALSE(c->readLine(2s));
  }
}

TEST_CASE("64 idle connections lock robots out only until the idle timeout",
          "[vision_app][robot_server]") {
  protocol::RobotServerOptions o = loopback();
  o.listen.idle_timeout = 1s;
  o.listen.max_per_address = 0;  // all from loopback: the total is what is tested
  Server s(o);
  std::vector<LineClient> idle;
  for (int i = 0; i < 64; ++i) {
    idle.push_back(s.connect());
    REQUIRE(*idle.back().request("PING", 2s) == "OK 4 PING");
  }
  CHECK(s.server->connections() == 64);
  {
    auto refused = s.connect();
    const auto reply = refused.readLine(2s);
    REQUIRE(reply);
    CHECK(reply->rfind("ERROR 13 ", 0) == 0);
  }
  // The idle ones are closed: a robot gets in again, without anyone leaving.
  bool served = false;
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (!served && std::chrono::steady_clock::now() < deadline) {
    auto robot = LineClient::connect("127.0.0.1", s.server->port(), 2s);
    if (robot) {
      auto r = robot->request("PING", 2s);
      served = r && *r == "OK 4 PING";
    }
    if (!served) std::this_thread::sleep_for(50ms);
  }
  CHECK(served);
}

TEST_CASE("a session's after-reply work runs once the reply is sent", "[robot_server]") {
  // The after-reply step waits until the client has read its reply: the
  // reply cannot be waiting behind it.
  std::promise<void> reply_read;
  std::shared_future<void> read = reply_read.get_future().share();
  std::atomic<int> ran{0};
  std::string client;
  std::string seen_reply;
  protocol::RobotServer server(loopback(), [&](std::string_view line, protocol::Session& session) {
    client = session.client;
    if (line == "LOCATE") {
      session.after_reply = [&, read](const std::string& reply) {
        read.wait();
        seen_reply = reply;
        ++ran;
      };
    }
    return "OK " + std::string(line);
  });
  server.start();
  auto c = LineClient::connect("127.0.0.1", server.port(), 2s);
  REQUIRE(c);
  CHECK(*c->request("LOCATE", 5s) == "OK LOCATE");
  CHECK(ran == 0);
  reply_read.set_value();
  // The connection's next request is served after that step.
  CHECK(*c->request("PING", 5s) == "OK PING");
  CHECK(ran == 1);
  CHECK(seen_reply == "OK LOCATE");
  CHECK(client.rfind("robot 127.0.0.1:", 0) == 0);
}
