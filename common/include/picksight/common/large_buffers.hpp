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
// reads image after image, before its threads:
// blocks up to 32 MiB come from the heap and freed memory is kept up to
// 128 MiB. Costs that much resident memory at most; a service that handles
// frames every second would map it again anyway.
void retainLargeBuffers();

}  // namespace picksight
