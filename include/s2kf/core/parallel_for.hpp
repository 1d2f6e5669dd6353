/// @file
/// Independent pieces of work spread over a few threads: the calibration's chunks, the marker-set
/// inference's template frames and attempts. Each piece writes only its own result, so what is
/// computed does not depend on the number of threads.
#pragma once

#include <algorithm>
#include <atomic>
#include <exception>
#include <thread>
#include <vector>

namespace s2kf {

/// Threads that use every core of this machine (at least one, where the count is unknown).
inline int every_core() { return static_cast<int>(std::max(1u, std::thread::hardware_concurrency())); }

/// Calls work(i) for i = 0 .. count - 1 on up to `threads` threads (the calling one included;
/// each takes the next i not yet taken). An exception thrown by work(i) stops the starting of
/// further pieces; once all threads are done, the one of the lowest i is rethrown, whatever the
/// threads.
template <class Work>
void parallel_for(int count, int threads, const Work& work) {
  threads = std::clamp(threads, 1, std::max(count, 1));
  std::vector<std::exception_ptr> failure(static_cast<std::size_t>(std::max(count, 0)));
  // Each thread takes the next piece not taken yet, so a thread the machine slows (or a piece
  // that takes longer) does not hold the others back. After a failure no piece is started; every
  // piece below it was started before it, so the lowest failing piece is always among those run.
  std::atomic<int> next{0};
  std::atomic<bool> failed{false};
  const auto run = [&] {
    while (!failed.load(std::memory_order_relaxed)) {
      const int i = next.fetch_add(1, std::memory_order_relaxed);
      if (i >= count) return;
      try {
        work(i);
      } catch (...) {
        failure[static_cast<std::size_t>(i)] = std::current_exception();
        failed = true;
      }
    }
  };
  std::vector<std::thread> workers;
  for (int t = 1; t < threads; ++t) workers.emplace_back(run);
  run();
  for (std::thread& worker : workers) worker.join();
  for (const std::exception_ptr& e : failure)
    if (e) std::rethrow_exception(e);
}

}  // namespace s2kf
