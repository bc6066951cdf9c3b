// picksight-robot end to end: the real binary against a real cell, in its
// three modes (arguments, stdin script, interactive on a terminal), with the
// exit codes scripts rely on.
#include <netinet/in.h>
#include <poll.h>
#include <pty.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include "cell_fixture.hpp"
#include "robot_cli.hpp"
#include "temp_dir.hpp"

using namespace picksight;
using namespace picksight::e2e;
using namespace std::chrono_literals;

namespace {

const std::string kSyntheticCamera = "cam0=synthetic:width=640,height=480,parts=4,seed=3";

std::string robotBin() { return binPath("picksight-robot"); }

// A TCP socket bound to a free loopback port; listening or not.
struct LocalSocket {
  explicit LocalSocket(bool listening) {
    fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    REQUIRE(fd >= 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    REQUIRE(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0);
    if (listening) REQUIRE(::listen(fd, 4) == 0);
    socklen_t len = sizeof(a);
    REQUIRE(::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0);
    port = ntohs(a.sin_port);
  }
  ~LocalSocket() { ::close(fd); }
  int fd = -1;
  uint16_t port = 0;
};

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

// Reads the pty until `needle` appears in what was read (or 10 s pass).
bool readUntil(int fd, const std::string& needle, std::string& seen) {
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (seen.find(needle) == std::string::npos) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) continue;
    char buf[512];
    const ssize_t n = ::read(fd, buf, sizeof(buf));
    if (n <= 0) return false;
    seen.append(buf, static_cast<size_t>(n));
  }
  return true;
}

}  // namespace

TEST_CASE("picksight-robot sends each argument as a request and exits 0 when all are OK",
          "[robot_cli]") {
  VideoServerProcess server({"--source", kSyntheticCamera, "--mode", "trigger"});
  VisionProcess vision(server);
  const auto r =
      run({robotBin(), "--port", std::to_string(vision.robot_port), "PING", "VERSION", "LOCATE 1"});
  CHECK(r.exit_code == robot::kExitOk);
  const auto out = lines(r.out);
  REQUIRE(out.size() == 3);
  CHECK(out[0] == "OK");
  CHECK(out[1].rfind("OK ", 0) == 0);
  CHECK(out[2].rfind("OK ", 0) == 0);
  CHECK_NOTHROW(parseLocateReply(out[2]));
}

TEST_CASE("picksight-robot exits 1 on an ERROR reply and still sends the other requests",
          "[robot_cli]") {
  VideoServerProcess server({"--source", kSyntheticCamera, "--mode", "trigger"});
  VisionProcess vision(server);
  const auto r = run({robotBin(), "--host", "127.0.0.1", "--port",
                      std::to_string(vision.robot_port), "LOCATE", "NOSUCH", "PING"});
  CHECK(r.exit_code == robot::kExitErrorReply);
  const auto out = lines(r.out);
  REQUIRE(out.size() == 3);
  CHECK(out[0].rfind("ERROR 11 ", 0) == 0);
  CHECK(out[1].rfind("ERROR 10 ", 0) == 0);
  CHECK(out[2] == "OK");
}

TEST_CASE("picksight-robot reads requests from stdin lines and skips blank lines and comments",
          "[robot_cli]") {
  VideoServerProcess server({"--source", kSyntheticCamera, "--mode", "trigger"});
  VisionProcess vision(server);
  const auto r = run({"/bin/sh", "-c",
                      "printf '# set-up\\nPING\\n\\n  \\nstatus\\r\\nLOCATE 1\\n' | '" +
                          robotBin() + "' --port " + std::to_string(vision.robot_port)});
  CHECK(r.exit_code == robot::kExitOk);
  const auto out = lines(r.out);
  REQUIRE(out.size() == 3);
  CHECK(out[0] == "OK");
  CHECK(out[1].rfind("OK frame=vision-px ", 0) == 0);
  CHECK_NOTHROW(parseLocateReply(out[2]));
}

TEST_CASE("picksight-robot exits 2 when nothing listens or no reply comes in time", "[robot_cli]") {
  SECTION("connection refused") {
    LocalSocket closed(false);  // bound, not listening: connections are refused
    const auto r = run({robotBin(), "--port", std::to_string(closed.port), "PING"});
    CHECK(r.exit_code == robot::kExitFailure);
    CHECK(r.out.empty());
  }
  SECTION("a server that accepts and never answers") {
    LocalSocket silent(true);
    const auto r =
        run({robotBin(), "--port", std::to_string(silent.port), "--timeout", "0.2", "PING"});
    CHECK(r.exit_code == robot::kExitFailure);
    CHECK(r.out.empty());
  }
  SECTION("the same from a script: the requests after the failure are not sent") {
    LocalSocket closed(false);
    const auto r = run(
        {"/bin/sh", "-c",
         "printf 'PING\\nPING\\n' | '" + robotBin() + "' --port " + std::to_string(closed.port)});
    CHECK(r.exit_code == robot::kExitFailure);
  }
}

TEST_CASE("picksight-robot refuses bad usage with exit code 2 before connecting", "[robot_cli]") {
  CHECK(run({robotBin(), "--port", "0", "PING"}).exit_code == robot::kExitFailure);
  CHECK(run({robotBin(), "--port", "70000", "PING"}).exit_code == robot::kExitFailure);
  CHECK(run({robotBin(), "--timeout", "-1", "PING"}).exit_code == robot::kExitFailure);
  CHECK(run({robotBin(), "--speed", "PING"}).exit_code == robot::kExitFailure);
  CHECK(run({robotBin(), "PING\nLOCATE 1"}).exit_code == robot::kExitFailure);
  const auto help = run({robotBin(), "--help"});
  CHECK(help.exit_code == robot::kExitOk);
  CHECK(help.out.find("--timeout") != std::string::npos);

  auto bad = robot::parseCommandLine({"PING\r"});
  REQUIRE_FALSE(bad);
  CHECK(bad.error().message.find("line break") != std::string::npos);
  auto good = robot::parseCommandLine({"--timeout", "1.5", "--host", "cell1", "PING"});
  REQUIRE(good);
  CHECK(good->timeout == 1500ms);
  CHECK(good->host == "cell1");
  CHECK(good->commands == std::vector<std::string>{"PING"});
}

TEST_CASE("picksight-robot reconnects once when the vision app closed an idle connection",
          "[robot_cli]") {
  // A server that closes the first connection after one reply, then answers
  // on the next: what an idle-timeout or a restart looks like to the client.
  LocalSocket listener(true);
  std::thread server([&] {
    for (int round = 0; round < 2; ++round) {
      const int c = ::accept(listener.fd, nullptr, nullptr);
      if (c < 0) return;
      char buf[64];
      if (::read(c, buf, sizeof(buf)) > 0) (void)!::write(c, "OK\n", 3);
      ::close(c);
    }
  });
  robot::RobotOptions options;
  options.port = listener.port;
  robot::RobotSession session(options);
  std::ostringstream out, err;
  CHECK(session.send("PING", out, err) == robot::kExitOk);
  CHECK(session.send("PING", out, err) == robot::kExitOk);
  server.join();
  CHECK(out.str() == "OK\nOK\n");
}

TEST_CASE("picksight-robot on a terminal prompts and answers and keeps a history", "[robot_cli]") {
  VideoServerProcess server({"--source", kSyntheticCamera, "--mode", "trigger"});
  VisionProcess vision(server);
  test::TempDir home;
  // Everything the child needs is made before the fork: after it, only
  // exec (the test process has threads).
  const std::string bin = robotBin();
  const std::string port = std::to_string(vision.robot_port);
  const std::string home_var = "HOME=" + home.path().string();
  const char* argv[] = {bin.c_str(), "--port", port.c_str(), nullptr};
  const char* envp[] = {home_var.c_str(), "TERM=dumb", nullptr};
  int master = -1;
  const pid_t pid = ::forkpty(&master, nullptr, nullptr, nullptr);
  REQUIRE(pid >= 0);
  if (pid == 0) {
    ::execve(bin.c_str(), const_cast<char* const*>(argv), const_cast<char* const*>(envp));
    ::_exit(127);
  }
  std::string seen;
  CHECK(readUntil(master, "> ", seen));
  CHECK(seen.find("connected to 127.0.0.1:") != std::string::npos);
  const std::string request = "STATUS\n";
  REQUIRE(::write(master, request.data(), request.size()) == static_cast<ssize_t>(request.size()));
  CHECK(readUntil(master, "OK frame=", seen));
  const std::string help = "HELP\n";
  REQUIRE(::write(master, help.data(), help.size()) == static_cast<ssize_t>(help.size()));
  CHECK(readUntil(master, "LOCATE <type>", seen));
  REQUIRE(::write(master, "quit\n", 5) == 5);
  // Reads what is left until the child exits and the pty closes.
  std::string ignored;
  readUntil(master, "\x01", ignored);
  ::close(master);
  int status = 0;
  REQUIRE(::waitpid(pid, &status, 0) == pid);
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == robot::kExitOk);
  std::ifstream history(home.file(".picksight_robot_history"));
  std::stringstream content;
  content << history.rdbuf();
  CHECK(content.str().find("STATUS") != std::string::npos);
  CHECK(content.str().find("HELP") != std::string::npos);
}
