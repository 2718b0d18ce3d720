// The heap policy for large short-lived arrays (solver/core/allocator.h): an array freed and
// allocated again reuses its pages instead of page-faulting through fresh ones.
#include <sys/resource.h>

#include <cstddef>
#include <vector>

#include <gtest/gtest.h>

#include "solver/core/allocator.h"

namespace {

long minor_faults() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_minflt;
}

// Fills a fresh array of `bytes` and returns one of its values (so that nothing is elided).
double touch_fresh_array(std::size_t bytes) {
  std::vector<double> a(bytes / sizeof(double));
  for (std::size_t i = 0; i < a.size(); i += 512) a[i] = static_cast<double>(i);
  volatile double last = a[a.size() - 512];
  return last;
}

TEST(HeapPolicy, ALargeArrayFreedAndAllocatedAgainReusesItsPages) {
  ASSERT_TRUE(systole::keep_freed_memory_in_heap());
  constexpr std::size_t kBytes = std::size_t{96} << 20;  // above glibc's largest mmap threshold (32 MiB)
  constexpr long kPages = static_cast<long>(kBytes / 4096);
  const long before_first = minor_faults();
  EXPECT_GT(touch_fresh_array(kBytes), 0.0);
  const long first = minor_faults() - before_first;
  const long before_second = minor_faults();
  EXPECT_GT(touch_fresh_array(kBytes), 0.0);
  const long second = minor_faults() - before_second;
  // The first array faults its pages in (at least a tenth of them, whatever the page size);
  // the second reuses them: fewer than 1 % of its pages fault.
  EXPECT_GT(first, kPages / 512 / 10) << "the first array should fault its pages in";
  EXPECT_LT(second, kPages / 100) << "the second array page-faulted " << second << " times for " << kPages
                                  << " pages: freed memory went back to the system";
}

}  // namespace
