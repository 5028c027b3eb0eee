#pragma once
// Private to the library: run fn(0), ..., fn(count - 1) on up to `threads` threads (the caller's
// among them), each index exactly once. Callers write each index's result to its own slot and
// combine the slots in index order afterwards, so the result does not depend on the thread
// count. The first exception (lowest index) is rethrown on the caller's thread after every
// worker has finished.
#include <algorithm>
#include <atomic>
#include <exception>
#include <thread>
#include <vector>

namespace scpkit::detail {

template <class Fn>
void parallel_for(int count, int threads, Fn&& fn) {
  const int workers = std::clamp(threads, 1, std::max(count, 1));
  if (workers == 1) {
    for (int i = 0; i < count; ++i) fn(i);
    return;
  }
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(count));
  std::atomic<int> next{0};
  auto work = [&] {
    for (int i = next.fetch_add(1); i < count; i = next.fetch_add(1)) {
      try {
        fn(i);
      } catch (...) {
        errors[static_cast<std::size_t>(i)] = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(workers - 1));
  for (int t = 1; t < workers; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

}  // namespace scpkit::detail
