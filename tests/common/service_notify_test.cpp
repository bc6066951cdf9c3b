// ServiceNotifier against a real notification socket: readiness, watchdog
// pings at the rate systemd asks, the stop notice, and silence without
// systemd.
#include "picksight/common/service_notify.hpp"

#include <stdlib.h>
#include <unistd.h>

#include <catch2/catch.hpp>

#include "notify_socket.hpp"

using namespace std::chrono_literals;
using picksight::ServiceNotifier;
using picksight::test::NotifySocket;

namespace {

// Sets the variables systemd gives a Type=notify service for one test.
struct NotifyEnvironment {
  NotifyEnvironment(const std::string& socket, const std::string& watchdog_usec) {
    ::setenv("NOTIFY_SOCKET", socket.c_str(), 1);
    if (watchdog_usec.empty()) {
      ::unsetenv("WATCHDOG_USEC");
    } else {
      ::setenv("WATCHDOG_USEC", watchdog_usec.c_str(), 1);
    }
    ::setenv("WATCHDOG_PID", std::to_string(::getpid()).c_str(), 1);
  }
  ~NotifyEnvironment() {
    ::unsetenv("NOTIFY_SOCKET");
    ::unsetenv("WATCHDOG_USEC");
    ::unsetenv("WATCHDOG_PID");
  }
};

}  // namespace

TEST_CASE("ServiceNotifier sends READY with a status then STOPPING", "[common][notify]") {
  NotifySocket socket;
  const NotifyEnvironment env(socket.path(), "");
  ServiceNotifier notifier;
  notifier.ready("robot port 5600");
  auto ready = socket.receive(5s);
  REQUIRE(ready);
  CHECK(*ready == "READY=1\nSTATUS=robot port 5600");
  notifier.stopping();
  auto stopping = socket.receive(5s);
  REQUIRE(stopping);
  CHECK(*stopping == "STOPPING=1");
}

TEST_CASE("ServiceNotifier pings the watchdog until stopping", "[common][notify]") {
  NotifySocket socket;
  const NotifyEnvironment env(socket.path(), "100000");  // 100 ms: pings every 50 ms
  ServiceNotifier notifier;
  notifier.ready("up");
  REQUIRE(socket.waitFor("READY=1", 5s));
  // Several pings, not one: the thread keeps pinging.
  for (int i = 0; i < 3; ++i) REQUIRE(socket.waitFor("WATCHDOG=1", 5s));
  notifier.stopping();
  REQUIRE(socket.waitFor("STOPPING=1", 5s));
  // The watchdog thread is joined before STOPPING=1: nothing follows it.
  CHECK_FALSE(socket.receive(300ms));
}

TEST_CASE("ServiceNotifier pings no watchdog meant for another process", "[common][notify]") {
  NotifySocket socket;
  const NotifyEnvironment env(socket.path(), "100000");
  ::setenv("WATCHDOG_PID", std::to_string(::getpid() + 1).c_str(), 1);
  ServiceNotifier notifier;
  notifier.ready("up");
  REQUIRE(socket.waitFor("READY=1", 5s));
  notifier.stopping();
  // STOPPING=1 is the next message: no ping came in between.
  auto next = socket.receive(5s);
  REQUIRE(next);
  CHECK(*next == "STOPPING=1");
}

TEST_CASE("ServiceNotifier does nothing without systemd", "[common][notify]") {
  ::unsetenv("NOTIFY_SOCKET");
  ::setenv("WATCHDOG_USEC", "100000", 1);
  ServiceNotifier notifier;
  notifier.ready("up");
  notifier.stopping();
  ::unsetenv("WATCHDOG_USEC");
  SUCCEED("no socket, no error, no thread left running");
}
