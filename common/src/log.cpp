// Line logger: a whole line per write(2) so lines from threads never interleave.
#include "picksight/common/log.hpp"

#include <unistd.h>

#include <atomic>
#include <ctime>
#include <mutex>

namespace picksight {
namespace {
std::atomic<LogLevel> g_level{LogLevel::kInfo};
std::mutex g_prefix_mutex;
std::string g_prefix = "picksight";  // guarded by g_prefix_mutex
}  // namespace

void setLogLevel(LogLevel level) { g_level = level; }

void setLogPrefix(std::string prefix) {
  std::lock_guard<std::mutex> lock(g_prefix_mutex);
  g_prefix = std::move(prefix);
}

void logLine(LogLevel level, const std::string& message) {
  if (level < g_level.load()) return;
  static const char* const kNames[] = {"debug", "info", "warning", "error"};
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  tm parts{};
  gmtime_r(&ts.tv_sec, &parts);
  char stamp[32];
  strftime(stamp, sizeof(stamp), "%H:%M:%S", &parts);
  std::string line;
  {
    std::lock_guard<std::mutex> lock(g_prefix_mutex);
    line = std::string(stamp) + "." + std::to_string(ts.tv_nsec / 1000000 + 1000).substr(1) + " " +
           g_prefix + " " + kNames[static_cast<int>(level)] + ": " + message + "\n";
  }
  const char* p = line.data();
  size_t left = line.size();
  while (left > 0) {
    ssize_t n = ::write(STDERR_FILENO, p, left);
    if (n <= 0) break;
    p += n;
    left -= static_cast<size_t>(n);
  }
}

}  // namespace picksight
