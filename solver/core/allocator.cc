#include "solver/core/allocator.h"

#include <malloc.h>

#include <limits>

namespace systole {

bool keep_freed_memory_in_heap() {
  // M_MMAP_MAX = 0: no allocation gets its own mapping (glibc still maps when the heap cannot
  // grow). M_TRIM_THRESHOLD at its largest: freed memory at the heap's top is not returned.
  const bool no_mmap = mallopt(M_MMAP_MAX, 0) == 1;
  const bool no_trim = mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max()) == 1;
  return no_mmap && no_trim;
}

}  // namespace systole
