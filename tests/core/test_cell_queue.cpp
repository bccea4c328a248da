// The approximate search's cell queue (core/support/cell_queue.h) against
// std::priority_queue: same pops on random priorities with many ties, the
// first pushed first among equals, and the key's order is the priority's.
#include <gtest/gtest.h>

#include <cstdint>
#include <functional>
#include <limits>
#include <queue>
#include <utility>
#include <vector>

#include "core/support/cell_queue.h"
#include "core/support/rng.h"

namespace kg {
namespace {

TEST(CellQueue, KeysOrderLikePrioritiesThenPushOrder) {
  const double priorities[] = {0.0, 1e-30, 0.5, 1.0, 1.0000001, 3.0, 1e10, 1e38, 1e300};
  for (std::size_t i = 0; i + 1 < std::size(priorities); ++i) {
    EXPECT_LT(pending_key(priorities[i], 7), pending_key(priorities[i + 1], 0)) << i;
    EXPECT_LT(pending_key(priorities[i], 0), pending_key(priorities[i], 1)) << i;
  }
  // Negative and NaN priorities rank as 0.
  EXPECT_EQ(pending_key(-2.0, 3), pending_key(0.0, 3));
  EXPECT_EQ(pending_key(std::numeric_limits<double>::quiet_NaN(), 3), pending_key(0.0, 3));
}

TEST(CellQueue, PopsLikeStdPriorityQueue) {
  Rng rng(5);
  constexpr int kCapacity = 512;
  std::vector<PendingCell> heap(kCapacity);
  for (int round = 0; round < 200; ++round) {
    int size = 0;
    std::uint32_t order = 0;
    // Reference: smallest (priority, order) first.
    using Entry = std::pair<std::uint64_t, int>;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<>> reference;
    const int levels = 1 + static_cast<int>(rng.uniform(40u));  // few levels: many ties
    for (int step = 0; step < 3000; ++step) {
      const bool push = size == 0 || (size < kCapacity && rng.uniform(3u) != 0);
      if (push) {
        const double priority =
            static_cast<double>(rng.uniform(static_cast<std::uint32_t>(levels)));
        const int cell = static_cast<int>(rng.uniform(100000u));
        const PendingCell x{pending_key(priority, order++), cell};
        push_pending(heap.data(), size, x);
        reference.push({x.key, cell});
      } else {
        const PendingCell top = pop_pending(heap.data(), size);
        ASSERT_EQ(top.key, reference.top().first) << round << " " << step;
        ASSERT_EQ(top.cell, reference.top().second) << round << " " << step;
        reference.pop();
      }
      ASSERT_EQ(static_cast<std::size_t>(size), reference.size());
    }
    // Draining yields the rest in order.
    while (size > 0) {
      ASSERT_EQ(pop_pending(heap.data(), size).key, reference.top().first);
      reference.pop();
    }
  }
}

TEST(CellQueue, EqualPrioritiesComeOutFirstPushedFirst) {
  std::vector<PendingCell> heap(64);
  int size = 0;
  for (int i = 0; i < 50; ++i)
    push_pending(heap.data(), size, {pending_key(2.0, static_cast<std::uint32_t>(i)), i});
  for (int i = 0; i < 50; ++i) EXPECT_EQ(pop_pending(heap.data(), size).cell, i);
  EXPECT_EQ(size, 0);
}

}  // namespace
}  // namespace kg
