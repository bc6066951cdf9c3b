// picksight-web beside clients that never finish their requests: sockets
// trickling header bytes hold no server thread, meet a deadline that no byte
// restarts, and one address cannot take more than --per-address
// connections; the page answers meanwhile.
#include <atomic>
#include <thread>

#include "raw_http.hpp"
#include "web_fixture.hpp"

namespace picksight::webtest {
namespace {
using namespace std::chrono_literals;
using e2e::VideoServerProcess;

// Opens `count` connections spread over loopback source addresses
// 127.0.0.<first>.. (`per_source` each), each with an unfinished request.
std::vector<RawSocket> slowSockets(int port, int count, int first, int per_source) {
  std::vector<RawSocket> sockets;
  for (int i = 0; i < count; ++i) {
    RawSocket s(port, "127.0.0." + std::to_string(first + i / per_source));
    REQUIRE(s.valid());
    REQUIRE(s.send("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n"));
    sockets.push_back(std::move(s));
  }
  return sockets;
}

}  // namespace

TEST_CASE("the page is served beside 200 sockets trickling header bytes", "[web][security]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  WebProcess web(videoServerArgs(server));
  // 200 sockets from 20 addresses, more than the server's 64 threads, each
  // sending a header byte every 200 ms (a thread each, per-byte timeouts,
  // locked everyone out for as long as they kept on).
  auto sockets = slowSockets(web.port, 200, 2, 10);
  std::atomic<bool> done{false};
  std::thread trickle([&] {
    while (!done) {
      for (auto& s : sockets) s.send("X");
      std::this_thread::sleep_for(200ms);
    }
  });
  std::this_thread::sleep_for(500ms);
  auto client = web.client();
  auto page = client.Get("/");
  auto cameras = client.Get("/api/cameras");
  done = true;
  trickle.join();
  REQUIRE(page);
  CHECK(page->status == 200);
  CHECK(page->body.find("PickSight") != std::string::npos);
  REQUIRE(cameras);
  CHECK(cameras->status == 200);
}

TEST_CASE("a request trickled byte by byte is cut off at the header deadline", "[web][security]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  auto args = videoServerArgs(server);
  args.insert(args.end(), {"--header-timeout", "1"});
  WebProcess web(args);
  RawSocket slow(web.port);
  REQUIRE(slow.valid());
  REQUIRE(slow.send("GET /api/cameras HTTP/1.1\r\nHost: 127.0.0.1\r\n"));
  // A byte every 100 ms: a timeout restarted by each byte never ends.
  std::string response;
  const auto give_up = std::chrono::steady_clock::now() + 20s;
  while (std::chrono::steady_clock::now() < give_up) {
    if (!slow.send("X")) break;
    response += slow.readAll(100ms);
    if (!response.empty()) break;
  }
  CHECK(statusOf(response) == 408);
  CHECK(slow.closedByPeer(5s));
  // A request that arrives whole is served as ever.
  auto res = web.client().Get("/api/cameras");
  REQUIRE(res);
  CHECK(res->status == 200);
}

TEST_CASE("one address holds at most --per-address connections", "[web][security]") {
  VideoServerProcess server({"--source", "cam0=synthetic:width=320,height=240", "--fps", "5"});
  auto args = videoServerArgs(server);
  args.insert(args.end(), {"--per-address", "4"});
  WebProcess web(args);
  auto held = slowSockets(web.port, 4, 40, 4);
  RawSocket fifth(web.port, "127.0.0.40");
  REQUIRE(fifth.valid());
  const std::string refused = fifth.readAll(5s);
  CHECK(statusOf(refused) == 503);
  CHECK(bodyOf(refused).find("--per-address") != std::string::npos);
  // Another address is served; and this one again once its sockets close.
  RawSocket other(web.port, "127.0.0.41");
  REQUIRE(other.valid());
  REQUIRE(other.send("GET /api/cameras HTTP/1.1\r\nHost: 127.0.0.1\r\n" + web.cookieLine() +
                     "Connection: close\r\n\r\n"));
  CHECK(statusOf(other.readAll()) == 200);
  held.clear();
  CHECK(pollUntil([&] {
    RawSocket again(web.port, "127.0.0.40");
    return again.valid() &&
           again.send("GET /api/cameras HTTP/1.1\r\nHost: 127.0.0.1\r\n" + web.cookieLine() +
                      "Connection: close\r\n\r\n") &&
           statusOf(again.readAll(5s)) == 200;
  }));
}

}  // namespace picksight::webtest
