// Bounded line framing of the robot protocol: bytes in, request lines out.
// A line longer than the limit is reported once and skipped up to its end,
// so the connection stays in step with the client; memory stays bounded
// whatever the client sends. Apart from the socket so that the fuzzer
// drives the very code the server runs.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <string_view>

namespace picksight::protocol {

class LineFramer {
 public:
  // Called per complete line (without LF or CR LF); false stops the feed.
  using LineHandler = std::function<bool(std::string_view line)>;
  // Called once per line over the limit; false stops the feed.
  using TooLongHandler = std::function<bool()>;

  explicit LineFramer(size_t max_line) : max_line_(max_line) {}

  // False when a handler asked to stop (the connection is then dropped).
  bool feed(std::string_view bytes, const LineHandler& on_line, const TooLongHandler& on_too_long);

  // Bytes held of an incomplete line (at most max_line + what one feed adds).
  size_t pending() const { return buffer_.size(); }

 private:
  const size_t max_line_;
  std::string buffer_;
  bool discarding_ = false;  // inside an over-long line, skipping to its end
};

}  // namespace picksight::protocol
