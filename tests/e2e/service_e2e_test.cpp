// The services as systemd runs them: the packaged example configuration
// (deploy/etc/picksight), readiness once the sockets are bound, watchdog
// pings, the stop notice, all through a real notification socket.
#include <stdlib.h>

#include <csignal>

#include <catch2/catch.hpp>

#include "cell_fixture.hpp"
#include "notify_socket.hpp"
#include "picksight/common/text.hpp"
#include "temp_dir.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace picksight::tool_support;
using namespace std::chrono_literals;

namespace {

// deploy/etc/picksight beside tests/data in the source tree.
std::string exampleConfig(const std::string& name) {
  return std::string(PICKSIGHT_TEST_DATA_DIR) + "/../../deploy/etc/picksight/" + name;
}

// Starts argv with NOTIFY_SOCKET and WATCHDOG_USEC (200 ms) in its
// environment, as systemd starts a Type=notify unit with WatchdogSec=.
std::unique_ptr<Subprocess> startNotified(const std::vector<std::string>& argv,
                                          const test::NotifySocket& socket) {
  ::setenv("NOTIFY_SOCKET", socket.path().c_str(), 1);
  ::setenv("WATCHDOG_USEC", "200000", 1);
  auto process = std::make_unique<Subprocess>(argv);
  ::unsetenv("NOTIFY_SOCKET");
  ::unsetenv("WATCHDOG_USEC");
  return process;
}

// READY=1 comes once, after the process printed its bound endpoints; pings
// follow.
void requireReadyAndPings(test::NotifySocket& socket) {
  auto ready = socket.waitFor("READY=1", 20s);
  REQUIRE(ready);
  CHECK(ready->find("STATUS=") != std::string::npos);
  REQUIRE(socket.waitFor("WATCHDOG=1", 10s));
  REQUIRE(socket.waitFor("WATCHDOG=1", 10s));
}

}  // namespace

TEST_CASE("Services on the example configuration notify systemd and answer LOCATE",
          "[e2e][service]") {
  test::NotifySocket server_socket;
  // The example file's cameras; the ports are the test's own free ones.
  auto server = startNotified(
      {binPath("picksight-video-server"), "--config", exampleConfig("video-server.yaml"),
       "--frames", "tcp://127.0.0.1:*", "--control", "tcp://127.0.0.1:*"},
      server_socket);
  auto frames = server->waitForLine("frames ", 10s);
  auto control = server->waitForLine("control ", 10s);
  REQUIRE(frames);
  REQUIRE(control);
  requireReadyAndPings(server_socket);

  test::TempDir data;
  test::NotifySocket vision_socket;
  auto vision =
      startNotified({binPath("picksight-vision"), "--config", exampleConfig("vision/cam0.yaml"),
                     "--frames", *frames, "--control", *control, "--robot-port", "0", "--bind",
                     "127.0.0.1", "--data-dir", data.path().string()},
                    vision_socket);
  auto port = vision->waitForLine("robot ", 10s);
  REQUIRE(port);
  requireReadyAndPings(vision_socket);

  auto robot =
      LineClient::connect("127.0.0.1", static_cast<uint16_t>(parseInt(*port).value_or(0)), 5s);
  REQUIRE(robot);
  auto reply = robot->request("LOCATE 1", 20s);
  REQUIRE(reply);
  CHECK(reply->rfind("OK ", 0) == 0);

  vision->kill(SIGTERM);
  REQUIRE(vision_socket.waitFor("STOPPING=1", 10s));
  REQUIRE(vision->wait(20s));
  server->kill(SIGTERM);
  REQUIRE(server_socket.waitFor("STOPPING=1", 10s));
  REQUIRE(server->wait(20s));
}
