// WorkerPool (core/support/worker_pool.h): every task runs once, on any
// thread count; in a run with help, the runs that a task starts from
// inside it (nested) run every one of their tasks once too, also when two
// tasks start one at the same time, and a thread out of tasks takes part.
#include "core/support/worker_pool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

namespace kg {
namespace {

TEST(WorkerPool, RunsEveryTaskOnce) {
  for (int threads : {1, 2, 3, 4}) {
    WorkerPool pool(threads);
    for (int round = 0; round < 50; ++round) {
      std::vector<int> ran(97, 0);
      std::atomic<int> bad_worker{0};
      auto task = [&](int i, int worker) {
        ++ran[static_cast<std::size_t>(i)];
        if (worker < 0 || worker >= threads) ++bad_worker;
      };
      pool.run(static_cast<int>(ran.size()), task);
      for (int r : ran) ASSERT_EQ(r, 1) << threads << " threads";
      EXPECT_EQ(bad_worker.load(), 0);
    }
  }
}

// Outer tasks that each start nested runs; returns whether every nested
// task ran exactly once and whether a thread other than the task's own ran
// some of them.
void run_nested(WorkerPool& pool, bool help, int outer, bool& all_once, bool& helped) {
  constexpr int kNested = 64;
  std::vector<std::vector<int>> counts(static_cast<std::size_t>(outer),
                                       std::vector<int>(kNested, 0));
  std::atomic<int> by_others{0};
  auto task = [&](int o, int worker) {
    for (int rep = 0; rep < 4; ++rep) {
      std::vector<int>& c = counts[static_cast<std::size_t>(o)];
      auto nested = [&](int i, int w) {
        ++c[static_cast<std::size_t>(i)];
        if (w != worker) ++by_others;
        // Enough work that an idle thread has time to join.
        volatile double x = 0;
        for (int k = 0; k < 20000; ++k) x = x + k * 0.5;
      };
      pool.run(kNested, nested);
    }
  };
  if (help) {
    pool.run_with_help(outer, task);
  } else {
    pool.run(outer, task);
  }
  all_once = true;
  for (const std::vector<int>& c : counts)
    for (int v : c) all_once = all_once && v == 4;
  helped = by_others.load() > 0;
}

TEST(WorkerPool, NestedRunsRunEveryTaskOnce) {
  for (int threads : {1, 2, 3, 4}) {
    WorkerPool pool(threads);
    for (bool help : {false, true}) {
      for (int outer : {1, 2, 3, 5}) {
        for (int round = 0; round < 5; ++round) {
          bool all_once = false, helped = false;
          run_nested(pool, help, outer, all_once, helped);
          EXPECT_TRUE(all_once) << threads << " threads, help " << help << ", " << outer
                                << " outer tasks";
          // Without help a nested run stays on its task's thread (one
          // outer task runs on the caller, its runs are not nested).
          if ((!help && outer > 1) || threads == 1) {
            EXPECT_FALSE(helped);
          }
        }
      }
    }
  }
}

TEST(WorkerPool, IdleThreadsHelpTheLastTask) {
  // Two outer tasks on 2 threads: one returns at once, the other starts a
  // nested run whose tasks, on the outer task's own thread, wait until
  // another thread has run one of them. Only the thread out of tasks can:
  // without its help the wait runs out (10 s). On one CPU the waiting
  // thread yields, so the helper gets its turn there too.
  WorkerPool pool(2);
  constexpr int kNested = 16;
  std::vector<int> ran(kNested, 0);
  std::atomic<int> by_others{0};
  std::atomic<bool> waited_out{false};
  auto outer = [&](int o, int worker) {
    if (o != 0) return;
    auto nested = [&](int i, int w) {
      ++ran[static_cast<std::size_t>(i)];
      if (w != worker) {
        ++by_others;
        return;
      }
      const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
      while (by_others.load() == 0 && !waited_out.load()) {
        if (std::chrono::steady_clock::now() > give_up) waited_out = true;
        std::this_thread::yield();
      }
    };
    pool.run(kNested, nested);
  };
  pool.run_with_help(2, outer);
  for (int r : ran) EXPECT_EQ(r, 1);
  EXPECT_FALSE(waited_out.load()) << "no thread helped the nested run";
  EXPECT_GT(by_others.load(), 0);
}

}  // namespace
}  // namespace kg
