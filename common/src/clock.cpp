// Clock helpers (see clock.hpp for which clock is for what).
#include "picksight/common/clock.hpp"

#include <ctime>

namespace picksight {
namespace {
uint64_t readClock(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<uint64_t>(ts.tv_nsec);
}
}  // namespace

uint64_t realtimeNs() { return readClock(CLOCK_REALTIME); }
uint64_t monotonicNs() { return readClock(CLOCK_MONOTONIC); }

}  // namespace picksight
