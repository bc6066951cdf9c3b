// The log of requests and connections the web server refuses: the first
// refusal of an address is logged with its reason, later ones only counted
// and summed up at most once a minute per address, so a flood of refusals
// costs a few lines, not one each.
//
// Threading: every member may be called from any thread (one mutex).
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>

namespace picksight::web {

class RefusalLog {
 public:
  // `what`: the port's name in the log lines ("HTTP").
  explicit RefusalLog(std::string what,
                      std::chrono::steady_clock::duration summary = std::chrono::minutes(1));

  // Counts one refusal of `address`; logs it when it is the address's first
  // or the summary interval has passed since its last line.
  void refused(const std::string& address, const std::string& reason);
  // Refusals of `address` so far (for tests and /metrics).
  uint64_t count(const std::string& address) const;
  uint64_t total() const;

 private:
  struct Entry {
    uint64_t count = 0;
    uint64_t unlogged = 0;
    std::chrono::steady_clock::time_point logged;
  };
  const std::string what_;
  const std::chrono::steady_clock::duration summary_;
  mutable std::mutex mutex_;
  std::map<std::string, Entry> entries_;  // under mutex_; bounded by kMaxAddresses
  uint64_t total_ = 0;                    // under mutex_
};

}  // namespace picksight::web
