// The selection's key sort and searches (core/selection/arc_keys.h) against the
// standard library on random lists of every size class they meet.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/selection/arc_keys.h"
#include "core/support/rng.h"

namespace kg {
namespace {

std::vector<std::uint64_t> random_keys(Rng& rng, std::uint32_t n, int bits) {
  std::vector<std::uint64_t> keys(n);
  const std::uint32_t ids = bits >= 32 ? 0xFFFFFFFFu : (std::uint32_t{1} << bits);
  // Sources from a small pool, so lists repeat them as a look-up's model
  // arcs do (several arcs leave one keypoint).
  std::vector<std::uint32_t> sources(std::max<std::uint32_t>(1, n / 4));
  for (auto& v : sources) v = static_cast<std::uint32_t>(rng.uniform(ids));
  for (auto& k : keys) {
    const std::uint32_t from = sources[rng.uniform(static_cast<std::uint32_t>(sources.size()))];
    const auto to = static_cast<std::uint32_t>(rng.uniform(ids));
    k = arc_key(from, to);
  }
  return keys;
}

TEST(ArcKeys, IdBits) {
  EXPECT_EQ(id_bits(0), 0);
  EXPECT_EQ(id_bits(1), 0);
  EXPECT_EQ(id_bits(2), 1);
  EXPECT_EQ(id_bits(3103), 12);
  EXPECT_EQ(id_bits(4096), 12);
  EXPECT_EQ(id_bits(4097), 13);
  EXPECT_EQ(id_bits(0xFFFFFFFFu), 32);
}

TEST(ArcKeys, RadixSortEqualsStdSort) {
  Rng rng(5);
  const int bit_cases[] = {0, 1, 5, 8, 12, 13, 16, 17, 24, 32};
  const std::uint32_t sizes[] = {0, 1, 2, 3, 15, 16, 17, 31, 190, 1000, 4096};
  for (int bits : bit_cases) {
    for (std::uint32_t n : sizes) {
      std::vector<std::uint64_t> keys = random_keys(rng, n, bits);
      std::vector<std::uint64_t> expected = keys;
      std::sort(expected.begin(), expected.end());
      std::vector<std::uint64_t> scratch(n);
      sort_arc_keys(keys.data(), scratch.data(), n, bits);
      ASSERT_EQ(keys, expected) << "bits " << bits << " n " << n;
    }
  }
}

TEST(ArcKeys, SortsReversedSortedListsByTheSourceAlone) {
  Rng rng(7);
  for (int bits : {3, 12, 17}) {
    for (std::uint32_t n : {0u, 5u, 17u, 190u, 2000u}) {
      std::vector<std::uint64_t> keys = random_keys(rng, n, bits);
      std::sort(keys.begin(), keys.end());
      for (auto& k : keys) k = arc_key(key_to(k), key_from(k));  // in order of `to` now
      std::vector<std::uint64_t> expected = keys;
      std::sort(expected.begin(), expected.end());
      std::vector<std::uint64_t> scratch(n);
      sort_arc_keys(keys.data(), scratch.data(), n, bits, true);
      ASSERT_EQ(keys, expected) << "bits " << bits << " n " << n;
    }
  }
}

TEST(ArcKeys, SearchesEqualStdLowerBound) {
  Rng rng(6);
  for (std::uint32_t n : {0u, 1u, 2u, 5u, 64u, 190u, 777u}) {
    std::vector<std::uint64_t> keys = random_keys(rng, n, 6);  // many repeats
    std::sort(keys.begin(), keys.end());
    for (std::uint32_t from = 0; from < 66; ++from) {
      for (std::uint32_t to = 0; to < 66; to += 5) {
        const std::uint64_t k = arc_key(from, to);
        ASSERT_EQ(lower_bound_key(keys.data(), n, k) - keys.data(),
                  std::lower_bound(keys.begin(), keys.end(), k) - keys.begin());
        ASSERT_EQ(contains_key(keys.data(), n, k), std::binary_search(keys.begin(), keys.end(), k));
      }
      const std::uint64_t *begin = nullptr, *end = nullptr;
      keys_from(keys.data(), n, from, begin, end);
      const auto range = std::equal_range(
          keys.begin(), keys.end(), arc_key(from, 0),
          [](std::uint64_t a, std::uint64_t b) { return key_from(a) < key_from(b); });
      ASSERT_EQ(begin - keys.data(), range.first - keys.begin());
      ASSERT_EQ(end - keys.data(), range.second - keys.begin());
    }
  }
}

}  // namespace
}  // namespace kg
