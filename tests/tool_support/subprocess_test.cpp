// Pins child processes with piped stdout: reading lines, EOF, exit statuses,
// SIGTERM then SIGKILL, and that a dropped Subprocess leaves no child behind.
#include <signal.h>
#include <sys/wait.h>

#include <cerrno>
#include <chrono>
#include <stdexcept>
#include <thread>

#include <catch2/catch.hpp>

#include "picksight/tool_support/subprocess.hpp"

using namespace std::chrono_literals;
using picksight::tool_support::Subprocess;

namespace {
constexpr auto kTimeout = 10000ms;

// Polls running(), which reaps the child, until it has exited by itself.
bool waitForExit(Subprocess& child) {
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  while (child.running()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(5ms);
  }
  return true;
}
}  // namespace

TEST_CASE("Subprocess reads the lines of /bin/echo, then EOF", "[common]") {
  Subprocess echo({"/bin/echo", "hello", "world"});
  CHECK(echo.pid() > 0);
  CHECK(echo.readLine(kTimeout) == std::optional<std::string>("hello world"));
  CHECK(echo.readLine(kTimeout) == std::nullopt);
  // EOF comes before the exit: wait for it, or terminate() would kill it.
  REQUIRE(waitForExit(echo));
  const int status = echo.terminate();
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  CHECK_FALSE(echo.running());
}

TEST_CASE("Subprocess waitForLine skips to the line with the prefix", "[common]") {
  Subprocess sh({"/bin/sh", "-c", "echo starting; echo frames tcp://127.0.0.1:4242; echo tail"});
  CHECK(sh.waitForLine("frames ", kTimeout) == std::optional<std::string>("tcp://127.0.0.1:4242"));
  CHECK(sh.readLine(kTimeout) == std::optional<std::string>("tail"));
  CHECK(sh.waitForLine("never ", kTimeout) == std::nullopt);
}

TEST_CASE("Subprocess keeps the exit status of a child that ended by itself", "[common]") {
  Subprocess sh({"/bin/sh", "-c", "exit 3"});
  REQUIRE(waitForExit(sh));
  CHECK_FALSE(sh.running());
  const int status = sh.terminate();
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 3);
}

TEST_CASE("Subprocess terminate stops sleep 100 with SIGTERM", "[common]") {
  Subprocess sleeper({"/bin/sleep", "100"});
  CHECK(sleeper.running());
  // Nothing on stdout: readLine times out and the child keeps running.
  CHECK(sleeper.readLine(100ms) == std::nullopt);
  CHECK(sleeper.running());
  const int status = sleeper.terminate(kTimeout);
  REQUIRE(WIFSIGNALED(status));
  CHECK(WTERMSIG(status) == SIGTERM);
  CHECK_FALSE(sleeper.running());
  // A second terminate returns the same status without signalling anyone.
  CHECK(sleeper.terminate() == status);
}

TEST_CASE("Subprocess terminate escalates to SIGKILL after the grace period", "[common]") {
  // exec keeps the ignored disposition, so the sleep itself ignores SIGTERM.
  Subprocess stubborn({"/bin/sh", "-c", "trap '' TERM; echo ready; exec /bin/sleep 100"});
  REQUIRE(stubborn.readLine(kTimeout) == std::optional<std::string>("ready"));
  const int status = stubborn.terminate(200ms);
  REQUIRE(WIFSIGNALED(status));
  CHECK(WTERMSIG(status) == SIGKILL);
}

TEST_CASE("Subprocess destructor terminates and reaps a running child", "[common]") {
  pid_t pid = -1;
  {
    Subprocess sleeper({"/bin/sleep", "100"});
    pid = sleeper.pid();
    REQUIRE(sleeper.running());
  }
  // Reaped: the pid no longer names a process (not even a zombie) of ours.
  errno = 0;
  CHECK(::waitpid(pid, nullptr, WNOHANG) == -1);
  CHECK(errno == ECHILD);
}

TEST_CASE("Subprocess of a missing program throws at start", "[common]") {
  CHECK_THROWS_AS(Subprocess({"/nonexistent/picksight-no-such-binary"}), std::runtime_error);
  CHECK_THROWS_AS(Subprocess(std::vector<std::string>{}), std::invalid_argument);
}
