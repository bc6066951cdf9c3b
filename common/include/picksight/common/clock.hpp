// Time stamps shared by every process: CLOCK_REALTIME for stamps that cross
// process boundaries (frame host timestamps), CLOCK_MONOTONIC for intervals.
#pragma once

#include <cstdint>

namespace picksight {

// Nanoseconds since the epoch; comparable between processes on one host.
uint64_t realtimeNs();
// Nanoseconds of a steady clock; only for measuring intervals.
uint64_t monotonicNs();

}  // namespace picksight
