// Robot TCP server framing and robustness, over real sockets.
#include <catch2/catch.hpp>

#include <atomic>
#include <thread>

#include "picksight/tool_support/line_client.hpp"
#include "picksight/protocol/robot_server.hpp"

using namespace picksight;
using namespace std::chrono_literals;

namespace {
// Echoes the request's length and text so framing mistakes show.
std::string echo(std::string_view line) {
  return "OK " + std::to_string(line.size()) + " " + std::string(line.substr(0, 32));
}

struct Server {
  explicit Server(size_t max_connections = 64) {
    app::RobotServerOptions o;
    o.bind_address = "127.0.0.1";
    o.port = 0;
    o.max_connections = max_connections;
    server = std::make_unique<app::RobotServer>(o, echo);
    server->start();
  }
  LineClient connect() {
    auto c = LineClient::connect("127.0.0.1", server->port(), 2s);
    REQUIRE(c);
    return std::move(*c);
  }
  std::unique_ptr<app::RobotServer> server;
};
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
  auto a = s.connect();
  auto b = s.connect();
  CHECK(*a.request("PING", 2s) == "OK 4 PING");
  CHECK(*b.request("PING", 2s) == "OK 4 PING");
  auto c = s.connect();
  const auto reply = c.readLine(2s);
  REQUIRE(reply);
  CHECK(reply->rfind("ERROR 13 ", 0) == 0);
  a.close();
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
