// Refusals logged once per address, then counted.
#include "picksight/web/refusal_log.hpp"

#include "picksight/common/log.hpp"

namespace picksight::web {
namespace {
// Beyond this many addresses the table starts again (logging each address's
// next refusal anew): a scan of a whole network costs memory in bound.
constexpr size_t kMaxAddresses = 4096;
}  // namespace

RefusalLog::RefusalLog(std::string what, std::chrono::steady_clock::duration summary)
    : what_(std::move(what)), summary_(summary) {}

void RefusalLog::refused(const std::string& address, const std::string& reason) {
  const auto now = std::chrono::steady_clock::now();
  std::lock_guard<std::mutex> lock(mutex_);
  ++total_;
  if (entries_.size() >= kMaxAddresses && entries_.count(address) == 0) entries_.clear();
  Entry& e = entries_[address];
  ++e.count;
  if (e.count == 1) {
    e.logged = now;
    logWarning("refused ", what_, " from ", address, ": ", reason,
               " (further refusals of this address are counted, logged once a minute)");
    return;
  }
  ++e.unlogged;
  if (now - e.logged < summary_) return;
  logWarning("refused ", what_, " from ", address, " ", e.unlogged, " more times (", e.count,
             " in all); the last: ", reason);
  e.unlogged = 0;
  e.logged = now;
}

uint64_t RefusalLog::count(const std::string& address) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = entries_.find(address);
  return it == entries_.end() ? 0 : it->second.count;
}

uint64_t RefusalLog::total() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return total_;
}

}  // namespace picksight::web
