// Robot protocol line framing.
#include "picksight/protocol/line_framer.hpp"

namespace picksight::protocol {

bool LineFramer::feed(std::string_view bytes, const LineHandler& on_line,
                      const TooLongHandler& on_too_long) {
  buffer_.append(bytes.data(), bytes.size());
  size_t start = 0;
  bool alive = true;
  for (;;) {
    const size_t nl = buffer_.find('\n', start);
    if (nl == std::string::npos) break;
    std::string_view line(buffer_.data() + start, nl - start);
    start = nl + 1;
    if (discarding_) {
      discarding_ = false;  // the end of the over-long line: already answered
      continue;
    }
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    alive = line.size() > max_line_ ? on_too_long() : on_line(line);
    if (!alive) break;
  }
  buffer_.erase(0, start);
  if (!alive) return false;
  if (discarding_) {
    buffer_.clear();
  } else if (buffer_.size() > max_line_) {
    buffer_.clear();
    discarding_ = true;
    return on_too_long();
  }
  return true;
}

}  // namespace picksight::protocol
