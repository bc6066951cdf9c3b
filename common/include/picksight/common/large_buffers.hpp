// Large buffers (frames, masks, filter intermediates: megabytes each, made
// and freed on every request) stay in the process instead of going back to
// the kernel. By default glibc maps such blocks fresh and unmaps them on
// free, so every request touched about 1200 new pages (4.7 MB) of zeroed
// memory: 2 to 3 ms of page faults per LOCATE at 1920x1080, more than the
// frame's transfer. Measured with /proc/<pid>/stat minflt around 300
// LOCATEs; see docs/ARCHITECTURE.md.
#pragma once

namespace picksight {

// Call once at the start of a long-running service, or of a command that
// reads image after image (the offline commands, the test main, the
// benchmarks that run the vision pass in their own process:
// picksight-bench-front-light on one condition made 335 K page faults and
// 2.0 s of system time without, 43 K and 0.4 s with), before its threads:
// blocks up to 32 MiB come from the heap and freed memory is kept up to
// 128 MiB. Costs that much resident memory at most; a service that handles
// frames every second would map it again anyway.
void retainLargeBuffers();

}  // namespace picksight
