/// @file
/// Independent pieces of work spread over a few threads: the calibration's chunks, the marker-set
/// inference's template frames and attempts. Each piece writes only its own result, so what is
/// computed does not depend on the number of threads.
#pragma once

#include <algorithm>
#include <exception>
#include <thread>
#include <vector>

namespace s2kf {

/// Calls work(i) for i = 0 .. count - 1 on up to `threads` threads (the calling one included;
/// thread t takes i = t, t + threads, ...). An exception thrown by work(i) stops that thread's
/// pieces; once all threads are done, the one of the lowest i is rethrown, whatever the threads.
template <class Work>
void parallel_for(int count, int threads, const Work& work) {
  threads = std::clamp(threads, 1, std::max(count, 1));
  std::vector<std::exception_ptr> failure(static_cast<std::size_t>(std::max(count, 0)));
  const auto run = [&](int t) {
    for (int i = t; i < count; i += threads) {
      try {
        work(i);
      } catch (...) {
        failure[static_cast<std::size_t>(i)] = std::current_exception();
        return;
      }
    }
  };
  std::vector<std::thread> workers;
  for (int t = 1; t < threads; ++t) workers.emplace_back(run, t);
  run(0);
  for (std::thread& worker : workers) worker.join();
  for (const std::exception_ptr& e : failure)
    if (e) std::rethrow_exception(e);
}

}  // namespace s2kf
