// glibc's allocator told to keep large blocks (see large_buffers.hpp).
#include "picksight/common/large_buffers.hpp"

#include <malloc.h>

namespace picksight {

void retainLargeBuffers() {
  // Setting either value also turns off glibc's dynamic threshold, which
  // would otherwise move them back as blocks are freed.
  mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024);
  mallopt(M_TRIM_THRESHOLD, 128 * 1024 * 1024);
}

}  // namespace picksight
