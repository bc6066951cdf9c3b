// Pins the robot-protocol line client against a small TCP server in the test:
// line framing (LF, CR LF, split and merged reads), timeouts, closed peers.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

#include <catch2/catch.hpp>

#include "picksight/tool_support/line_client.hpp"

using namespace std::chrono_literals;
using picksight::tool_support::LineClient;

namespace {

// Generous: a loaded machine must never turn a passing test into a timeout.
constexpr auto kTimeout = 10000ms;

// A TCP server on 127.0.0.1 and a kernel-chosen port, serving one connection
// at a time on its own thread.
class TestServer {
 public:
  enum class Behaviour { kEcho, kSilent, kCloseAtOnce };

  explicit TestServer(Behaviour behaviour) : behaviour_(behaviour) {
    listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (listen_fd_ < 0) throw std::runtime_error("socket");
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = 0;
    socklen_t len = sizeof(addr);
    if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0 ||
        ::listen(listen_fd_, 4) != 0 ||
        ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
      ::close(listen_fd_);
      throw std::runtime_error("bind/listen");
    }
    port_ = ntohs(addr.sin_port);
    thread_ = std::thread([this] { serve(); });
  }
  ~TestServer() {
    stop_ = true;
    thread_.join();
    ::close(listen_fd_);
  }
  TestServer(const TestServer&) = delete;
  TestServer& operator=(const TestServer&) = delete;

  uint16_t port() const { return port_; }

 private:
  // Waits for `fd` to be readable, checking the stop flag every 50 ms.
  bool readable(int fd) {
    while (!stop_) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 50) > 0) return true;
    }
    return false;
  }

  void serve() {
    while (readable(listen_fd_)) {
      const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
      if (fd < 0) continue;
      if (behaviour_ != Behaviour::kCloseAtOnce) {
        char buf[4096];
        while (readable(fd)) {
          const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
          if (n <= 0) break;
          if (behaviour_ == Behaviour::kEcho)
            (void)::send(fd, buf, static_cast<size_t>(n), MSG_NOSIGNAL);
        }
      }
      ::close(fd);
    }
  }

  const Behaviour behaviour_;
  int listen_fd_ = -1;
  uint16_t port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// A port on which nothing listens (bound, then released).
uint16_t closedPort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof(addr);
  ::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr));
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  ::close(fd);
  return ntohs(addr.sin_port);
}

}  // namespace

TEST_CASE("LineClient request returns the reply line without its line ending", "[common]") {
  TestServer server(TestServer::Behaviour::kEcho);
  auto client = LineClient::connect("127.0.0.1", server.port(), kTimeout);
  REQUIRE(client);
  CHECK(client->isOpen());
  auto reply = client->request("LOCATE part_a", kTimeout);
  REQUIRE(reply);
  CHECK(*reply == "LOCATE part_a");
  // CR LF is accepted as a line end and stripped.
  REQUIRE(client->sendRaw("STORE 1.5 2.5\r\n"));
  auto line = client->readLine(kTimeout);
  REQUIRE(line);
  CHECK(*line == "STORE 1.5 2.5");
}

TEST_CASE("LineClient reassembles split lines and splits merged ones", "[common]") {
  TestServer server(TestServer::Behaviour::kEcho);
  auto client = LineClient::connect("localhost", server.port(), kTimeout);
  REQUIRE(client);
  REQUIRE(client->sendRaw("first\nsecond\r\nthi"));
  REQUIRE(client->sendRaw("rd\n"));
  for (const char* expected : {"first", "second", "third"}) {
    auto line = client->readLine(kTimeout);
    REQUIRE(line);
    CHECK(*line == expected);
  }
  // An empty line is a line.
  auto empty = client->request("", kTimeout);
  REQUIRE(empty);
  CHECK(empty->empty());
}

TEST_CASE("LineClient readLine times out when no line comes and stays usable", "[common]") {
  TestServer server(TestServer::Behaviour::kSilent);
  auto client = LineClient::connect("127.0.0.1", server.port(), kTimeout);
  REQUIRE(client);
  REQUIRE(client->sendRaw("HELLO\n"));
  auto line = client->readLine(100ms);
  CHECK_FALSE(line);
  CHECK(client->isOpen());
}

TEST_CASE("LineClient reports a connection closed by the server", "[common]") {
  TestServer server(TestServer::Behaviour::kCloseAtOnce);
  auto client = LineClient::connect("127.0.0.1", server.port(), kTimeout);
  REQUIRE(client);
  auto line = client->readLine(kTimeout);
  REQUIRE_FALSE(line);
  CHECK_FALSE(line.error().message.empty());
}

TEST_CASE("LineClient connect to a port nobody listens on is an error", "[common]") {
  auto client = LineClient::connect("127.0.0.1", closedPort(), kTimeout);
  REQUIRE_FALSE(client);
  CHECK_THAT(client.error().message, Catch::Contains("127.0.0.1"));
}

TEST_CASE("LineClient moves its connection and closes cleanly", "[common]") {
  TestServer server(TestServer::Behaviour::kEcho);
  auto connected = LineClient::connect("127.0.0.1", server.port(), kTimeout);
  REQUIRE(connected);
  LineClient client = std::move(*connected);
  CHECK_FALSE(connected->isOpen());
  REQUIRE(client.isOpen());
  auto reply = client.request("PING", kTimeout);
  REQUIRE(reply);
  CHECK(*reply == "PING");
  client.close();
  CHECK_FALSE(client.isOpen());
  CHECK_FALSE(client.sendRaw("PING\n"));
  CHECK_FALSE(client.readLine(10ms));
}
