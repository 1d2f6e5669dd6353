// parallel_for: every piece runs once whatever the thread count, and a failure is rethrown as the
// lowest failing piece's, so the caller sees the same result and the same error on any machine.
#include <s2kf/core/parallel_for.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

TEST(ParallelFor, EveryPieceRunsOnceOnAnyNumberOfThreads) {
  for (const int threads : {1, 2, 3, 8, 40}) {
    std::vector<int> runs(37, 0);
    std::atomic<int> total{0};
    s2kf::parallel_for(static_cast<int>(runs.size()), threads, [&](int i) {
      ++runs[static_cast<std::size_t>(i)];
      total += i;
    });
    EXPECT_EQ(runs, std::vector<int>(37, 1)) << threads << " threads";
    EXPECT_EQ(total.load(), 36 * 37 / 2);
  }
  int calls = 0;
  s2kf::parallel_for(0, 4, [&](int) { ++calls; });
  EXPECT_EQ(calls, 0);
}

TEST(ParallelFor, TheLowestFailingPieceIsRethrownWhateverTheThreads) {
  for (const int threads : {1, 2, 5}) {
    try {
      s2kf::parallel_for(10, threads, [](int i) {
        if (i == 3 || i == 4 || i == 8) throw std::runtime_error("piece " + std::to_string(i));
      });
      ADD_FAILURE() << "nothing thrown with " << threads << " threads";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), "piece 3") << threads << " threads";
    }
  }
}

TEST(ParallelFor, NoPieceStartsAfterAFailure) {
  // One thread takes the pieces in order: the failing piece is the last one run.
  std::vector<int> runs(10, 0);
  EXPECT_THROW(s2kf::parallel_for(10, 1,
                                  [&](int i) {
                                    ++runs[static_cast<std::size_t>(i)];
                                    if (i == 4) throw std::runtime_error("piece 4");
                                  }),
               std::runtime_error);
  EXPECT_EQ(runs, (std::vector<int>{1, 1, 1, 1, 1, 0, 0, 0, 0, 0}));
}

}  // namespace
