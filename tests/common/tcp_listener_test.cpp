// The TCP listener both PickSight ports share: the total and per-address
// caps, the allow-list, slots freed by their connections, and the bound on
// refusal log lines. Clients come from 127.0.0.1 and 127.0.0.2 (both
// loopback) so that two addresses can be told apart on one host.
#include "picksight/common/tcp_listener.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <string>
#include <vector>

namespace picksight {
namespace {

// A connected client socket from `from`, or an invalid one.
Socket connectFrom(const char* from, uint16_t port) {
  Socket s(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0));
  REQUIRE(s.valid());
  sockaddr_in local{};
  local.sin_family = AF_INET;
  REQUIRE(::inet_pton(AF_INET, from, &local.sin_addr) == 1);
  REQUIRE(::bind(s.fd(), reinterpret_cast<sockaddr*>(&local), sizeof(local)) == 0);
  sockaddr_in remote{};
  remote.sin_family = AF_INET;
  remote.sin_port = htons(port);
  ::inet_pton(AF_INET, "127.0.0.1", &remote.sin_addr);
  REQUIRE(::connect(s.fd(), reinterpret_cast<sockaddr*>(&remote), sizeof(remote)) == 0);
  return s;
}

// Waits for the peer the client just connected and takes it.
std::optional<TcpListener::Connection> acceptOne(TcpListener& listener) {
  pollfd p{listener.fd(), POLLIN, 0};
  REQUIRE(::poll(&p, 1, 5000) == 1);
  return listener.accept();
}

// What the server sent before closing (the refusal reply), read to EOF.
std::string readAll(const Socket& s) {
  std::string text;
  char chunk[256];
  for (;;) {
    pollfd p{s.fd(), POLLIN, 0};
    if (::poll(&p, 1, 5000) != 1) break;
    const ssize_t n = ::recv(s.fd(), chunk, sizeof(chunk), 0);
    if (n <= 0) break;
    text.append(chunk, static_cast<size_t>(n));
  }
  return text;
}

struct Fixture {
  explicit Fixture(TcpListenerOptions options)
      : listener(
            "test port", withLoopback(std::move(options)),
            [](TcpListener::Refusal why, const std::string& text) {
              const char* kind = why == TcpListener::Refusal::kNotAllowed ? "NOT ALLOWED"
                                 : why == TcpListener::Refusal::kTooMany  ? "TOO MANY"
                                                                          : "TOO MANY FROM";
              return std::string(kind) + ": " + text + "\n";
            },
            [this](const std::string& line) { log.push_back(line); }) {}
  static TcpListenerOptions withLoopback(TcpListenerOptions options) {
    options.bind_address = "127.0.0.1";
    options.port = 0;
    return options;
  }
  std::vector<std::string> log;
  TcpListener listener;
};

}  // namespace

TEST_CASE("refusals of one address are logged at the 1st and each tenfold count",
          "[common][listener]") {
  std::vector<uint64_t> logged;
  for (uint64_t n = 1; n <= 100000; ++n)
    if (refusalLogged(n)) logged.push_back(n);
  CHECK(logged == std::vector<uint64_t>{1, 10, 100, 1000, 10000, 100000});
}

TEST_CASE("the total cap refuses with its reason and a released slot admits again",
          "[common][listener]") {
  TcpListenerOptions options;
  options.max_connections = 2;
  options.max_per_address = 0;
  Fixture f(options);
  auto a = connectFrom("127.0.0.1", f.listener.port());
  auto b = connectFrom("127.0.0.2", f.listener.port());
  auto first = acceptOne(f.listener);
  auto second = acceptOne(f.listener);
  REQUIRE(first);
  REQUIRE(second);
  CHECK(first->peerAddress() == "127.0.0.1");
  CHECK(second->peerAddress() == "127.0.0.2");
  CHECK(second->peerPort() != 0);
  CHECK(f.listener.connections() == 2);

  auto c = connectFrom("127.0.0.2", f.listener.port());
  CHECK_FALSE(acceptOne(f.listener));
  CHECK(readAll(c) == "TOO MANY: too many connections (limit 2)\n");
  CHECK(f.listener.refusals() == 1);

  second->releaseSlot();
  second->releaseSlot();  // once only
  CHECK(f.listener.connections() == 1);
  auto d = connectFrom("127.0.0.2", f.listener.port());
  auto third = acceptOne(f.listener);
  REQUIRE(third);
  first.reset();  // destroyed: its slot goes with it
  CHECK(f.listener.connections() == 1);
}

TEST_CASE("the per-address cap refuses one address and admits another", "[common][listener]") {
  TcpListenerOptions options;
  options.max_connections = 8;
  options.max_per_address = 2;
  Fixture f(options);
  std::vector<Socket> clients;
  std::vector<TcpListener::Connection> held;
  for (int i = 0; i < 2; ++i) {
    clients.push_back(connectFrom("127.0.0.1", f.listener.port()));
    auto c = acceptOne(f.listener);
    REQUIRE(c);
    held.push_back(std::move(*c));
  }
  auto refused = connectFrom("127.0.0.1", f.listener.port());
  CHECK_FALSE(acceptOne(f.listener));
  CHECK(readAll(refused) ==
        "TOO MANY FROM: too many connections from 127.0.0.1 (limit 2 per address)\n");
  auto other = connectFrom("127.0.0.2", f.listener.port());
  CHECK(acceptOne(f.listener));
  // A slot moved into another connection is still one slot.
  held[0] = std::move(held[1]);
  held.pop_back();
  CHECK(f.listener.connections() == 1);
  auto again = connectFrom("127.0.0.1", f.listener.port());
  CHECK(acceptOne(f.listener));
}

TEST_CASE("the allow-list refuses others and each refusal is logged a bounded number of times",
          "[common][listener]") {
  TcpListenerOptions options;
  options.allow = *AllowList::parse("127.0.0.2");
  Fixture f(options);
  auto allowed = connectFrom("127.0.0.2", f.listener.port());
  auto admitted = acceptOne(f.listener);
  CHECK(admitted);
  for (int i = 0; i < 25; ++i) {
    auto refused = connectFrom("127.0.0.1", f.listener.port());
    CHECK_FALSE(acceptOne(f.listener));
    CHECK(readAll(refused) == "NOT ALLOWED: address 127.0.0.1 is not allowed on this port\n");
  }
  CHECK(f.listener.refusals() == 25);
  // 25 refusals: logged at the 1st and the 10th, with the count.
  REQUIRE(f.log.size() == 2);
  CHECK(f.log[0].find("test port: refused 127.0.0.1 (address 127.0.0.1 is not allowed") == 0);
  CHECK(f.log[0].find("allow-list 127.0.0.2/32") != std::string::npos);
  CHECK(f.log[0].find("first refusal") != std::string::npos);
  CHECK(f.log[1].find("10 refusals of this address") != std::string::npos);
  CHECK(f.listener.connections() == 1);
}

TEST_CASE("a listener that cannot bind says which port", "[common][listener]") {
  Fixture f(TcpListenerOptions{});
  TcpListenerOptions taken;
  taken.bind_address = "127.0.0.1";
  taken.port = f.listener.port();
  try {
    TcpListener second("second port", taken);
    FAIL("bound a port already listened on");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find("second port: cannot listen on 127.0.0.1:" +
                                     std::to_string(taken.port)) == 0);
  }
  taken.bind_address = "not an address";
  CHECK_THROWS_WITH(TcpListener("third port", taken),
                    Catch::Contains("bad bind address 'not an address'"));
}

}  // namespace picksight
