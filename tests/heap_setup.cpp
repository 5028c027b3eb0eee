// Linked into every test program: the allocator settings the CLI's main makes
// (scpkit/memory.hpp), before any test runs, so tests see the CLI's memory behaviour.
#include "scpkit/memory.hpp"

namespace {

const bool kHeapSetUp = [] {
  scpkit::keep_large_blocks_in_the_heap();
  return true;
}();

}  // namespace
