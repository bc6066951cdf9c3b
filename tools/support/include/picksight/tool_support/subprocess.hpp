// A child process with its stdout readable line by line: used by the demo,
// the end-to-end tests and the benchmarks to start the real PickSight
// processes and read back the endpoints they bound.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace picksight::tool_support {

class Subprocess {
 public:
  // Starts argv[0] (a path) with the given arguments; stdout is piped to us,
  // stderr is inherited. Throws std::runtime_error if the process cannot start.
  explicit Subprocess(const std::vector<std::string>& argv);
  ~Subprocess();  // terminates the child if still running
  Subprocess(const Subprocess&) = delete;
  Subprocess& operator=(const Subprocess&) = delete;

  // Next line of stdout (without the newline), or nullopt on timeout or EOF.
  std::optional<std::string> readLine(std::chrono::milliseconds timeout);
  // Reads lines until one starts with `prefix`; returns the rest of that line.
  std::optional<std::string> waitForLine(const std::string& prefix,
                                         std::chrono::milliseconds timeout);

  // Waits for the child to exit by itself; its waitpid status, or nullopt if
  // it is still running after `timeout`.
  std::optional<int> wait(std::chrono::milliseconds timeout);
  // SIGTERM, then SIGKILL after `grace`; returns the exit status as from waitpid.
  int terminate(std::chrono::milliseconds grace = std::chrono::milliseconds(3000));
  // Sends a signal without waiting.
  void kill(int signal);
  bool running();
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  int stdout_fd_ = -1;
  std::string buffer_;
  std::optional<int> status_;
};

}  // namespace picksight::tool_support
