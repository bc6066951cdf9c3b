// libFuzzer target: arbitrary bytes through the robot server's line framing
// and the complete command table (VisionCell) with no camera. Every request
// must get exactly one reply line starting with OK or ERROR, and nothing may
// crash, hang or grow without bound.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "picksight/app/vision_cell.hpp"
#include "picksight/protocol/line_framer.hpp"

namespace {
// Small, so that over-long lines are reached often.
constexpr size_t kMaxLine = 512;

picksight::app::VisionCell& cell() {
  // A data directory of its own: without a camera and without models no
  // command can write, but a bug that did must not touch anyone's data.
  // A plain array: it outlives every static destructor, so the clean-up at
  // exit can still read it.
  static char dir[] = "/tmp/picksight-fuzz-XXXXXX";
  static const bool made = [] {
    if (!::mkdtemp(dir)) std::abort();
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(dir, ignored);
    });
    return true;
  }();
  (void)made;
  static picksight::app::VisionCell instance(dir, std::make_unique<picksight::link::NoCamera>(),
                                             picksight::cell::VisionOptions{});
  static const bool loaded = (instance.load(), true);
  (void)loaded;
  return instance;
}

void check(bool ok) {
  if (!ok) __builtin_trap();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto& vision = cell();
  picksight::protocol::LineFramer framer(kMaxLine);
  const auto on_line = [&](std::string_view line) {
    const std::string reply = vision.handle(line);
    check(reply.find('\n') == std::string::npos && reply.find('\r') == std::string::npos);
    check(reply == "OK" || reply.rfind("OK ", 0) == 0 || reply.rfind("ERROR ", 0) == 0);
    return true;
  };
  const auto on_too_long = [] { return true; };
  // Fed in uneven pieces, as TCP delivers them.
  size_t at = 0;
  size_t piece = 1;
  while (at < size) {
    const size_t n = std::min(piece, size - at);
    framer.feed(std::string_view(reinterpret_cast<const char*>(data) + at, n), on_line,
                on_too_long);
    check(framer.pending() <= kMaxLine + n);
    at += n;
    piece = piece * 3 % 97 + 1;
  }
  return 0;
}
