// builder/parallel.h: every index runs exactly once on any thread count, a
// failure stops the handing out with every lower index run, and an
// exception reaches the caller after the threads have finished.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstddef>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "builder/parallel.h"

namespace kg {
namespace {

TEST(Parallel, WorkerCountIsBoundedByItemsAndAtLeastOne) {
  EXPECT_EQ(worker_count(4, 10), 4);
  EXPECT_EQ(worker_count(4, 3), 3);
  EXPECT_EQ(worker_count(1, 100), 1);
  EXPECT_EQ(worker_count(3, 0), 1);
  const int all = worker_count(0, 1000);
  EXPECT_GE(all, 1);
  EXPECT_EQ(all, static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
}

TEST(Parallel, EveryIndexRunsOnceOnAnyThreadCount) {
  constexpr std::size_t kCount = 1000;
  for (int threads : {1, 2, 3, 8}) {
    std::vector<std::atomic<int>> runs(kCount);
    std::mutex mutex;
    std::set<std::thread::id> workers;
    parallel_for(kCount, threads, [&](std::size_t i) {
      runs[i].fetch_add(1);
      const std::lock_guard<std::mutex> lock(mutex);
      workers.insert(std::this_thread::get_id());
      return true;
    });
    for (std::size_t i = 0; i < kCount; ++i) ASSERT_EQ(runs[i].load(), 1) << i << ", " << threads;
    EXPECT_LE(workers.size(), static_cast<std::size_t>(threads));
    EXPECT_TRUE(workers.count(std::this_thread::get_id()) == 1 || threads > 1)
        << "one thread: the caller's";
  }
}

TEST(Parallel, NothingToDoCallsNothing) {
  bool called = false;
  parallel_for(0, 4, [&](std::size_t) {
    called = true;
    return true;
  });
  EXPECT_FALSE(called);
}

TEST(Parallel, FailureStopsTheHandingOutAfterEveryLowerIndexRan) {
  // The failure lies late and lands while lower indices are still running
  // (every seventh sleeps): a split into fixed ranges per thread would
  // leave the first ranges unfinished.
  constexpr std::size_t kCount = 400, kFailing = 300;
  for (int threads : {1, 2, 4}) {
    std::vector<std::atomic<int>> runs(kCount);
    parallel_for(kCount, threads, [&](std::size_t i) {
      if (i % 7 == 0) std::this_thread::sleep_for(std::chrono::microseconds(300));
      runs[i].fetch_add(1);
      return i != kFailing;
    });
    for (std::size_t i = 0; i <= kFailing; ++i) ASSERT_EQ(runs[i].load(), 1) << i;
    std::size_t ran = 0;
    for (std::size_t i = 0; i < kCount; ++i) ran += static_cast<std::size_t>(runs[i].load());
    // At most one index per other thread starts after the failure.
    EXPECT_LE(ran, kFailing + static_cast<std::size_t>(threads)) << threads << " threads";
  }
}

TEST(Parallel, TheLowestThrowingIndexIsRethrownAfterEveryLowerIndexRan) {
  for (int threads : {1, 2, 4}) {
    std::vector<std::atomic<int>> runs(100);
    try {
      parallel_for(runs.size(), threads, [&](std::size_t i) {
        runs[i].fetch_add(1);
        // Index 11 throws late, after 12 (on another thread) has thrown.
        if (i == 11) {
          std::this_thread::sleep_for(std::chrono::milliseconds(20));
          throw std::runtime_error("model 11");
        }
        if (i == 12) throw std::runtime_error("model 12");
        return true;
      });
      ADD_FAILURE() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "model 11") << threads << " threads";
    }
    for (std::size_t i = 0; i <= 11; ++i) EXPECT_EQ(runs[i].load(), 1) << i;
  }
}

TEST(Parallel, StatusWorkReturnsTheFirstFailureInIndexOrder) {
  for (int threads : {1, 2, 4}) {
    std::vector<std::atomic<int>> runs(200);
    // Index 41 fails late, after 42 (on another thread) has failed.
    const Status s = parallel_for_status(runs.size(), threads, [&](std::size_t i) {
      runs[i].fetch_add(1);
      if (i == 41) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        return Status{StatusCode::kInvalidArgument, "model 41"};
      }
      if (i == 42) return Status{StatusCode::kIoError, "model 42"};
      return Status::ok();
    });
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << threads << " threads";
    EXPECT_EQ(s.message(), "model 41") << threads << " threads";
    for (std::size_t i = 0; i <= 41; ++i) EXPECT_EQ(runs[i].load(), 1) << i;
  }
  EXPECT_TRUE(parallel_for_status(50, 3, [](std::size_t) { return Status::ok(); }));
}

}  // namespace
}  // namespace kg
