// The web HMI's login sessions and the login rate limit: a session is a
// random 256-bit token (libsodium's randombytes) that the browser holds in
// an HttpOnly, SameSite=Strict cookie, valid until it has been idle for
// idle_timeout or has lived for max_age, whichever comes first; logins
// from one address are limited to a few failures a minute.
//
// Threading: every member may be called from any thread (one mutex each).
#pragma once

#include <chrono>
#include <map>
#include <mutex>
#include <optional>
#include <string>

#include "picksight/web/user_store.hpp"

namespace picksight::web {

struct Session {
  std::string user;
  Role role = Role::kOperator;
};

class Sessions {
 public:
  using Clock = std::chrono::steady_clock;
  Sessions(std::chrono::seconds idle_timeout, std::chrono::seconds max_age,
           size_t max_sessions = 1024);

  // A new session's token (64 hex digits).
  std::string create(const Session& session);
  // The session of `token` if it is valid now; renews its idle time.
  std::optional<Session> find(const std::string& token);
  void remove(const std::string& token);
  // Ends every session of `user` (removed, or given another role).
  void removeUser(const std::string& user);
  std::chrono::seconds maxAge() const { return max_age_; }

 private:
  struct Entry {
    Session session;
    Clock::time_point created;
    Clock::time_point used;
  };
  const std::chrono::seconds idle_timeout_;
  const std::chrono::seconds max_age_;
  const size_t max_sessions_;
  std::mutex mutex_;
  std::map<std::string, Entry> sessions_;  // under mutex_
};

// Failed logins per address: after max_failures within window, every login
// from that address is refused until the window has passed since the last
// failure.
class LoginLimiter {
 public:
  using Clock = std::chrono::steady_clock;
  explicit LoginLimiter(int max_failures = 5,
                        std::chrono::seconds window = std::chrono::seconds(60));
  // Whether `address` may try now; when not, the seconds to wait.
  std::optional<std::chrono::seconds> blocked(const std::string& address);
  void failed(const std::string& address);
  void succeeded(const std::string& address);

 private:
  struct Entry {
    int failures = 0;
    Clock::time_point last;
  };
  const int max_failures_;
  const std::chrono::seconds window_;
  std::mutex mutex_;
  std::map<std::string, Entry> entries_;  // under mutex_; bounded (4096)
};

}  // namespace picksight::web
