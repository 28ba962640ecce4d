// SPDX-License-Identifier: BSD-3-Clause
// common/parallel.hpp: every index runs once whatever the number of threads, and a failure is
// reported as a serial loop would report it (the smallest failing index).

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/parallel.hpp"

namespace lidarcal {
namespace {

TEST(ParallelFor, EveryIndexRunsOnceWhateverTheThreads) {
  for (int threads : {1, 2, 3, 8}) {
    for (std::size_t n : {0u, 1u, 2u, 7u, 100u}) {
      SCOPED_TRACE(std::to_string(threads) + " threads, " + std::to_string(n) + " items");
      std::vector<std::atomic<int>> runs(n);
      parallelFor(n, threads, [&](std::size_t i) { ++runs[i]; });
      for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(runs[i].load(), 1) << i;
    }
  }
}

TEST(ParallelFor, TheFailureReportedIsTheOneASerialLoopMeetsFirst) {
  // Failing items at 11, 3 and 40 of 64; every run must report item 3, and every item below it
  // must have run.
  for (int threads : {1, 2, 4}) {
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<std::atomic<int>> runs(64);
      try {
        parallelFor(runs.size(), threads, [&](std::size_t i) {
          ++runs[i];
          if (i == 11 || i == 3 || i == 40) throw std::runtime_error("item " + std::to_string(i));
        });
        ADD_FAILURE() << "no exception";
      } catch (const std::runtime_error& e) {
        EXPECT_EQ(std::string(e.what()), "item 3") << threads << " threads";
      }
      for (std::size_t i = 0; i <= 3; ++i) EXPECT_EQ(runs[i].load(), 1) << i;
    }
  }
}

TEST(ParallelFor, AutomaticThreadsAreAtLeastOneAndCapped) {
  EXPECT_EQ(threadsFor(3), 3);
  EXPECT_GE(threadsFor(0), 1);
  EXPECT_LE(threadsFor(0, 2), 2);
}

}  // namespace
}  // namespace lidarcal
