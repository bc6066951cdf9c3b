// Bytes read from a stream, cut into lines: the one place the line client
// and the process launcher take a whole line out of what they have read.
#pragma once

#include <chrono>
#include <optional>
#include <string>

namespace picksight::tool_support {

// The first whole line of `buffer` (without its '\n'), taken out of it;
// none while no '\n' has arrived.
inline std::optional<std::string> takeLine(std::string& buffer) {
  const size_t nl = buffer.find('\n');
  if (nl == std::string::npos) return std::nullopt;
  std::string line = buffer.substr(0, nl);
  buffer.erase(0, nl + 1);
  return line;
}

// Milliseconds from now to `deadline` (zero or less once it has passed).
inline std::chrono::milliseconds timeLeft(std::chrono::steady_clock::time_point deadline) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(deadline -
                                                               std::chrono::steady_clock::now());
}

}  // namespace picksight::tool_support
