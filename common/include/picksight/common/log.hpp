// Minimal line logger to stderr: one line per call, safe from any thread.
#pragma once

#include <sstream>
#include <string>

namespace picksight {

enum class LogLevel { kDebug, kInfo, kWarning, kError };

void setLogLevel(LogLevel level);
void setLogPrefix(std::string prefix);  // process name shown on each line
void logLine(LogLevel level, const std::string& message);

namespace detail {
template <typename... Args>
std::string concat(const Args&... args) {
  std::ostringstream out;
  (out << ... << args);
  return out.str();
}
}  // namespace detail

template <typename... Args>
void logInfo(const Args&... args) {
  logLine(LogLevel::kInfo, detail::concat(args...));
}
template <typename... Args>
void logWarning(const Args&... args) {
  logLine(LogLevel::kWarning, detail::concat(args...));
}
template <typename... Args>
void logError(const Args&... args) {
  logLine(LogLevel::kError, detail::concat(args...));
}
template <typename... Args>
void logDebug(const Args&... args) {
  logLine(LogLevel::kDebug, detail::concat(args...));
}

}  // namespace picksight
