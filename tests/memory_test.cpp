// keep_large_blocks_in_the_heap: after it, a block of several MB is served from the heap, not
// from a fresh mapping (glibc's counters of mapped blocks do not move). Without glibc, or under
// the sanitizers (whose allocator replaces glibc's), there is nothing to check.
#include "scpkit/memory.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <vector>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace scpkit {
namespace {

TEST(Memory, LargeBlocksStayInTheHeap) {
#if !defined(__GLIBC__)
  GTEST_SKIP() << "not glibc";
#elif defined(SCPKIT_SANITIZED)
  GTEST_SKIP() << "the sanitizers' allocator replaces glibc's";
#else
  keep_large_blocks_in_the_heap();
  for (std::size_t mb : {1, 4, 16}) {
    const auto before = mallinfo2();
    std::vector<double> block(mb * 1024 * 1024 / sizeof(double), 1.0);
    const auto during = mallinfo2();
    EXPECT_EQ(during.hblks, before.hblks) << mb << " MB";
    EXPECT_EQ(during.hblkhd, before.hblkhd) << mb << " MB";
    EXPECT_GE(during.uordblks, before.uordblks + mb * 1024 * 1024) << mb << " MB";
    block.back() = 2.0;
    EXPECT_EQ(block.front() + block.back(), 3.0);
  }
#endif
}

}  // namespace
}  // namespace scpkit
