#pragma once
// Process-wide allocator settings for programs that run many identifications (the CLI, the test
// programs). Call it once, at the start of main; the library never calls it itself.

namespace scpkit {

/// The identifications allocate and free matrices of a few MB many times over (a Gram matrix
/// per held-out block and per solve: about 2 MB each at L = 30). Above glibc's default mmap
/// threshold each is a fresh mapping whose pages fault in again: a fifth of a voltage diagnosis
/// was system time (6.7 of 21 s; docs/diagnose-log.md, session 43). This keeps them in the heap
/// (glibc's largest mmap threshold, 32 MB; freed memory returned to the system only beyond
/// 1 GB). The results are the same and so is the peak memory. Does nothing without glibc.
void keep_large_blocks_in_the_heap();

}  // namespace scpkit
