// Login sessions and the login rate limit (sessions.hpp).
#include "picksight/web/sessions.hpp"

#include <sodium.h>

namespace picksight::web {

Sessions::Sessions(std::chrono::seconds idle_timeout, std::chrono::seconds max_age,
                   size_t max_sessions)
    : idle_timeout_(idle_timeout), max_age_(max_age), max_sessions_(max_sessions) {}

std::string Sessions::create(const Session& session) {
  unsigned char bytes[32];
  randombytes_buf(bytes, sizeof(bytes));
  char hex[2 * sizeof(bytes) + 1];
  sodium_bin2hex(hex, sizeof(hex), bytes, sizeof(bytes));
  const auto now = Clock::now();
  std::lock_guard<std::mutex> lock(mutex_);
  // Expired ones first; then, at the bound, the least recently used.
  for (auto it = sessions_.begin(); it != sessions_.end();)
    it = now - it->second.used > idle_timeout_ || now - it->second.created > max_age_
             ? sessions_.erase(it)
             : std::next(it);
  if (sessions_.size() >= max_sessions_) {
    auto oldest = sessions_.begin();
    for (auto it = sessions_.begin(); it != sessions_.end(); ++it)
      if (it->second.used < oldest->second.used) oldest = it;
    sessions_.erase(oldest);
  }
  sessions_[hex] = Entry{session, now, now};
  return hex;
}

std::optional<Session> Sessions::find(const std::string& token) {
  if (token.size() != 64) return std::nullopt;
  const auto now = Clock::now();
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = sessions_.find(token);
  if (it == sessions_.end()) return std::nullopt;
  if (now - it->second.used > idle_timeout_ || now - it->second.created > max_age_) {
    sessions_.erase(it);
    return std::nullopt;
  }
  it->second.used = now;
  return it->second.session;
}

void Sessions::remove(const std::string& token) {
  std::lock_guard<std::mutex> lock(mutex_);
  sessions_.erase(token);
}

void Sessions::removeUser(const std::string& user) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto it = sessions_.begin(); it != sessions_.end();)
    it = it->second.session.user == user ? sessions_.erase(it) : std::next(it);
}

LoginLimiter::LoginLimiter(int max_failures, std::chrono::seconds window)
    : max_failures_(max_failures), window_(window) {}

std::optional<std::chrono::seconds> LoginLimiter::blocked(const std::string& address) {
  const auto now = Clock::now();
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = entries_.find(address);
  if (it == entries_.end()) return std::nullopt;
  if (now - it->second.last >= window_) {
    entries_.erase(it);
    return std::nullopt;
  }
  if (it->second.failures < max_failures_) return std::nullopt;
  return std::chrono::duration_cast<std::chrono::seconds>(window_ - (now - it->second.last)) +
         std::chrono::seconds(1);
}

void LoginLimiter::failed(const std::string& address) {
  const auto now = Clock::now();
  std::lock_guard<std::mutex> lock(mutex_);
  if (entries_.size() >= 4096 && entries_.count(address) == 0) {
    for (auto it = entries_.begin(); it != entries_.end();)
      it = now - it->second.last >= window_ ? entries_.erase(it) : std::next(it);
    if (entries_.size() >= 4096) entries_.erase(entries_.begin());
  }
  Entry& e = entries_[address];
  if (now - e.last >= window_) e.failures = 0;
  ++e.failures;
  e.last = now;
}

void LoginLimiter::succeeded(const std::string& address) {
  std::lock_guard<std::mutex> lock(mutex_);
  entries_.erase(address);
}

}  // namespace picksight::web
