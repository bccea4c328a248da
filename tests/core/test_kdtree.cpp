// Flat kd-tree over arc descriptors in each encoding (float32, int16, int8):
// exact radius and k-nearest search against brute force in the same domain,
// quantisation and the scaled radius, and queries that allocate nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iterator>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/description/arc_descriptor.h"
#include "core/description/arc_types.h"
#include "core/description/descriptor_encoding.h"
#include "core/index/kdtree.h"
#include "core/index/leaf_scan.h"
#include "core/support/rng.h"
#include "support/alloc_counter.h"
#include "support/search_data.h"

namespace kg {
namespace {

// Descriptors in the domain of T: as computed for float, quantised otherwise.
template <class T>
KdPoint<T> encode(const ArcDescriptor& d) {
  if constexpr (std::is_same_v<T, float>) {
    return d;
  } else {
    return quantise<T>(d);
  }
}

template <class T>
std::vector<KdPoint<T>> encode_all(const std::vector<ArcDescriptor>& data) {
  std::vector<KdPoint<T>> out;
  for (const ArcDescriptor& d : data) out.push_back(encode<T>(d));
  return out;
}

// A search point in T's domain: the descriptor and two random scale
// attributes in [-0.1, 0.4).
template <class T>
KdPoint<T, kSearchDims> with_attributes(Rng& rng, const ArcDescriptor& d) {
  ArcSearchPoint p{};
  for (int i = 0; i < kDescriptorSize; ++i) p[i] = d[i];
  p[kDescriptorSize] = static_cast<float>(rng.uniform01() * 0.5 - 0.1);
  p[kDescriptorSize + 1] = static_cast<float>(rng.uniform01() * 0.5 - 0.1);
  if constexpr (std::is_same_v<T, float>) {
    return p;
  } else {
    return quantise<T>(p);
  }
}

// The squared radius in T's domain, as ArcSearch computes it.
template <class T>
typename KdTraits<T>::Dist radius2_of(float r) {
  using Dist = typename KdTraits<T>::Dist;
  if constexpr (std::is_same_v<T, float>) {
    return r * r;
  } else {
    std::int64_t scaled = 0;
    EXPECT_TRUE(scaled_radius2(r, encoding_of<T>(), std::numeric_limits<Dist>::max(), scaled));
    return static_cast<Dist>(scaled);
  }
}

template <class T>
struct Tree {
  std::vector<KdPoint<T>> points;
  std::vector<std::uint32_t> ids;
  std::vector<typename KdTraits<T>::Node> nodes;
  BasicKdTreeView<T> view;        // reports source ids
  BasicKdTreeView<T> slots_view;  // no ids: reports tree slots (the model index's way)
};

template <class T>
Tree<T> make_tree(const std::vector<KdPoint<T>>& data) {
  Tree<T> t;
  const auto n = static_cast<std::uint32_t>(data.size());
  build_kdtree<T>(data.data(), n, t.points, t.ids, t.nodes);
  t.view = BasicKdTreeView<T>(t.points.data(), t.ids.data(), n, t.nodes.data(), kdtree_depth(n));
  t.slots_view = BasicKdTreeView<T>(t.points.data(), nullptr, n, t.nodes.data(), kdtree_depth(n));
  return t;
}

template <class T>
class KdTreeTyped : public ::testing::Test {};
using Encodings = ::testing::Types<float, std::int16_t, std::int8_t>;
class EncodingName {
 public:
  template <class T>
  static std::string GetName(int) {
    return encoding_name(encoding_of<T>());
  }
};
TYPED_TEST_SUITE(KdTreeTyped, Encodings, EncodingName);

TYPED_TEST(KdTreeTyped, LayoutIsCompleteAndAPermutation) {
  using T = TypeParam;
  Rng rng(1);
  for (std::uint32_t n : {0u, 1u, 7u, 8u, 9u, 100u, 1000u, 4097u}) {
    const auto data = encode_all<T>(test::clustered_descriptors(rng, n));
    const Tree<T> t = make_tree<T>(data);
    EXPECT_EQ(t.nodes.size(), (std::size_t{1} << kdtree_depth(n)) - 1);
    std::vector<std::uint32_t> sorted = t.ids;
    std::sort(sorted.begin(), sorted.end());
    for (std::uint32_t i = 0; i < n; ++i) {
      ASSERT_EQ(sorted[i], i);
      EXPECT_EQ(t.points[i], data[t.ids[i]]);
    }
    // Every node separates its range: left <= split <= right on its dimension.
    const int depth = kdtree_depth(n);
    for (std::uint32_t node = 0; node < t.nodes.size(); ++node) {
      std::uint32_t b = 0, e = n, level = 0;
      for (std::uint32_t x = node + 1; x > 1; x /= 2) ++level;
      // Walk down from the root to find the node's range.
      std::uint32_t path = node + 1, at = 0;
      for (std::uint32_t l = level; l-- > 0;) {
        const std::uint32_t m = b + (e - b) / 2;
        if ((path >> l) & 1U) {
          b = m;
          at = 2 * at + 2;
        } else {
          e = m;
          at = 2 * at + 1;
        }
      }
      ASSERT_EQ(at, node);
      ASSERT_LT(static_cast<int>(level), depth);
      const auto dim = t.nodes[node].dim;
      ASSERT_LT(dim, static_cast<decltype(dim)>(kDescriptorSize));
      const std::uint32_t m = b + (e - b) / 2;
      for (std::uint32_t i = b; i < m; ++i) ASSERT_LE(t.points[i][dim], t.nodes[node].split);
      for (std::uint32_t i = m; i < e; ++i) ASSERT_GE(t.points[i][dim], t.nodes[node].split);
    }
  }
}

TYPED_TEST(KdTreeTyped, RadiusSearchEqualsBruteForce) {
  using T = TypeParam;
  Rng rng(2);
  for (std::uint32_t n : {1u, 50u, 3000u, 20000u}) {
    const auto data = encode_all<T>(test::clustered_descriptors(rng, n));
    const Tree<T> t = make_tree<T>(data);
    std::vector<std::uint32_t> out(n + 1);
    for (int q = 0; q < 100; ++q) {
      const KdPoint<T> query = encode<T>(test::clustered_descriptors(rng, 1)[0]);
      for (float r : {0.1f, 0.3f, 0.5f}) {
        const auto r2 = radius2_of<T>(r);
        std::vector<std::uint32_t> expected, expected_slots;
        for (std::uint32_t i = 0; i < n; ++i) {
          if (kd_distance2<T>(data[i], query) < r2) expected.push_back(i);
          if (kd_distance2<T>(t.points[i], query) < r2) expected_slots.push_back(i);
        }
        const auto cap = static_cast<std::uint32_t>(out.size());
        std::uint32_t found = t.view.radius_search(query, r2, out.data(), cap);
        std::vector<std::uint32_t> got(out.begin(), out.begin() + found);
        std::sort(got.begin(), got.end());
        EXPECT_EQ(got, expected) << "n " << n << " r " << r;
        found = t.slots_view.radius_search(query, r2, out.data(), cap);
        got.assign(out.begin(), out.begin() + found);
        std::sort(got.begin(), got.end());
        EXPECT_EQ(got, expected_slots) << "slots, n " << n << " r " << r;
      }
    }
  }
}

// Trees over descriptors plus two attributes (the model index's points):
// radius plus box equals brute force, with attributes clustered so the box
// cuts, and the tree splitting on them.
TYPED_TEST(KdTreeTyped, RadiusAndBoxSearchEqualsBruteForce) {
  using T = TypeParam;
  using Dist = typename KdTraits<T>::Dist;
  using Point = KdPoint<T, kSearchDims>;
  Rng rng(5);
  auto attributed = [&](const ArcDescriptor& d) { return with_attributes<T>(rng, d); };
  for (std::uint32_t n : {1u, 70u, 5000u, 20000u}) {
    std::vector<Point> data;
    for (const ArcDescriptor& d : test::clustered_descriptors(rng, n))
      data.push_back(attributed(d));
    std::vector<Point> points;
    std::vector<std::uint32_t> ids;
    std::vector<typename KdTraits<T>::Node> nodes;
    build_kdtree<T, kSearchDims>(data.data(), n, points, ids, nodes, 4.0);
    bool attribute_split = false;
    for (const auto& node : nodes) attribute_split |= node.dim >= kDescriptorSize;
    if (n >= 5000) {
      EXPECT_TRUE(attribute_split) << n;
    }
    const BasicKdTreeView<T, kSearchDims> view(points.data(), ids.data(), n, nodes.data(),
                                               kdtree_depth(n));
    std::vector<std::uint32_t> out(n + 1);
    std::size_t boxed = 0, unboxed = 0;
    for (int q = 0; q < 60; ++q) {
      const Point query = attributed(test::clustered_descriptors(rng, 1)[0]);
      const auto r2 = radius2_of<T>(0.4f);
      const auto box = static_cast<Dist>(
          std::is_same_v<T, float> ? 0.05 : 0.05 * encoding_scale(encoding_of<T>()));
      std::vector<std::uint32_t> expected;
      for (std::uint32_t i = 0; i < n; ++i) {
        bool inside = kd_distance2(data[i], query) < r2;
        for (int d = kDescriptorSize; d < kSearchDims; ++d) {
          const Dist diff = static_cast<Dist>(data[i][d]) - static_cast<Dist>(query[d]);
          inside = inside && (diff < 0 ? -diff : diff) <= box;
        }
        if (inside) expected.push_back(i);
      }
      std::uint32_t found =
          view.radius_search(query, r2, box, out.data(), static_cast<std::uint32_t>(out.size()));
      std::vector<std::uint32_t> got(out.begin(), out.begin() + found);
      std::sort(got.begin(), got.end());
      ASSERT_EQ(got, expected) << "n " << n << " query " << q;
      boxed += found;
      unboxed += view.radius_search(query, r2, out.data(), static_cast<std::uint32_t>(out.size()));
    }
    if (n >= 5000) {
      EXPECT_LT(boxed * 2, unboxed) << "the box should cut most matches";
    }
  }
}

// A tree over n clustered descriptors with random attributes (tree order,
// ids, nodes) and its leaf bounds.
template <class T>
struct AttributedTree {
  std::vector<KdPoint<T, kSearchDims>> points, bounds;
  std::vector<std::uint32_t> ids;
  std::vector<typename KdTraits<T>::Node> nodes;
  int depth = 0;
};
template <class T>
AttributedTree<T> attributed_tree(Rng& rng, std::uint32_t n) {
  std::vector<KdPoint<T, kSearchDims>> data;
  for (const ArcDescriptor& d : test::clustered_descriptors(rng, n))
    data.push_back(with_attributes<T>(rng, d));
  AttributedTree<T> t;
  build_kdtree<T, kSearchDims>(data.data(), n, t.points, t.ids, t.nodes, 4.0);
  t.depth = kdtree_depth(n);
  kdtree_leaf_bounds<T, kSearchDims>(t.points.data(), n, t.bounds);
  return t;
}

// Leaf bounds only skip leaves that cannot match (exact answers unchanged);
// the best-bin-first search returns a subset of the exact answer, all of it
// when it may visit every leaf, and most of it within 32 leaves.
TYPED_TEST(KdTreeTyped, LeafBoundsExactAndApproximateSearch) {
  using T = TypeParam;
  using Dist = typename KdTraits<T>::Dist;
  using Point = KdPoint<T, kSearchDims>;
  Rng rng(9);
  auto attributed = [&](const ArcDescriptor& d) { return with_attributes<T>(rng, d); };
  const std::uint32_t n = 20000;
  const AttributedTree<T> t = attributed_tree<T>(rng, n);
  const int depth = t.depth;
  ASSERT_EQ(t.bounds.size(), 2u << depth);
  const BasicKdTreeView<T, kSearchDims> plain(t.points.data(), t.ids.data(), n, t.nodes.data(),
                                              depth);
  const BasicKdTreeView<T, kSearchDims> bounded(t.points.data(), t.ids.data(), n, t.nodes.data(),
                                                depth, t.bounds.data());
  const auto r2 = radius2_of<T>(0.7f);
  const auto box =
      static_cast<Dist>(std::is_same_v<T, float> ? 0.2 : 0.2 * encoding_scale(encoding_of<T>()));
  std::vector<std::uint32_t> a(n + 1), b(n + 1);
  const auto cap = static_cast<std::uint32_t>(a.size());
  auto sorted = [](std::vector<std::uint32_t>& v, std::uint32_t count) {
    std::vector<std::uint32_t> out(v.begin(), v.begin() + count);
    std::sort(out.begin(), out.end());
    return out;
  };
  std::size_t exact_total = 0, approximate_total = 0;
  for (int q = 0; q < 60; ++q) {
    const Point query = attributed(test::clustered_descriptors(rng, 1)[0]);
    const auto exact = sorted(a, plain.radius_search(query, r2, box, a.data(), cap));
    ASSERT_EQ(sorted(b, bounded.radius_search(query, r2, box, b.data(), cap)), exact) << q;
    const int all_leaves = 1 << depth;
    ASSERT_EQ(
        sorted(b, bounded.radius_search_approximate(query, r2, box, all_leaves, b.data(), cap)),
        exact)
        << q;
    const auto some =
        sorted(b, bounded.radius_search_approximate(query, r2, box, 8, b.data(), cap));
    EXPECT_TRUE(std::includes(exact.begin(), exact.end(), some.begin(), some.end())) << q;
    // The 8 leaves visited first are the first 8 of 32: more leaves, more matches.
    const auto more =
        sorted(b, bounded.radius_search_approximate(query, r2, box, 32, b.data(), cap));
    EXPECT_TRUE(std::includes(more.begin(), more.end(), some.begin(), some.end())) << q;
    EXPECT_TRUE(std::includes(exact.begin(), exact.end(), more.begin(), more.end())) << q;
    exact_total += exact.size();
    approximate_total += some.size();
  }
  ASSERT_GT(exact_total, 0u);
  std::printf("approximate search, 8 leaves: %zu of %zu exact matches\n", approximate_total,
              exact_total);
  EXPECT_LT(approximate_total, exact_total);  // approximate indeed
  const Point query = attributed(test::clustered_descriptors(rng, 1)[0]);
  const test::AllocationCounter allocations;
  EXPECT_GE(bounded.radius_search_approximate(query, r2, box, 32, b.data(), cap), 0u);
  EXPECT_EQ(allocations.count(), 0);
}

// The search keeps at most as many pending cells as it has leaves left to
// visit (up to 64 leaves; a larger budget keeps them all in a heap): the
// leaves visited, and so the slots found in their order, are the first
// ones of a search with a larger budget. Given the arcs by slot, the same
// search writes each slot's arc key instead, in the same order.
TYPED_TEST(KdTreeTyped, ApproximateSearchOrderAndArcKeys) {
  using T = TypeParam;
  using Dist = typename KdTraits<T>::Dist;
  using Point = KdPoint<T, kSearchDims>;
  Rng rng(17);
  const std::uint32_t n = 20000;
  const AttributedTree<T> t = attributed_tree<T>(rng, n);
  // Slots as ids, as the model index's tree.
  const BasicKdTreeView<T, kSearchDims> tree(t.points.data(), nullptr, n, t.nodes.data(), t.depth,
                                             t.bounds.data());
  std::vector<std::uint32_t> from(n);
  std::vector<std::int16_t> to_offset(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    from[i] = rng.uniform(1u << 20);
    to_offset[i] = static_cast<std::int16_t>(static_cast<int>(rng.uniform(60001)) - 30000);
  }
  const KdArcKeys keys{from.data(), to_offset.data()};
  const auto r2 = radius2_of<T>(0.7f);
  const auto box =
      static_cast<Dist>(std::is_same_v<T, float> ? 0.2 : 0.2 * encoding_scale(encoding_of<T>()));
  std::vector<std::uint32_t> all(n), some(n);
  std::vector<std::uint64_t> arc_keys(n);
  int prefixes = 0;
  for (int q = 0; q < 40; ++q) {
    const Point query = with_attributes<T>(rng, test::clustered_descriptors(rng, 1)[0]);
    const std::uint32_t total = tree.radius_search_approximate(query, r2, box, 80, all.data(), n);
    for (int leaves : {1, 8, 24, 64}) {
      const std::uint32_t found =
          tree.radius_search_approximate(query, r2, box, leaves, some.data(), n);
      ASSERT_LE(found, total) << q << " " << leaves;
      ASSERT_TRUE(std::equal(some.begin(), some.begin() + found, all.begin()))
          << q << " " << leaves;
      prefixes += found > 0 && found < total ? 1 : 0;
      const std::uint32_t cap = found / 2;  // also cut short
      ASSERT_EQ(tree.radius_search_approximate(query, r2, box, leaves, keys, arc_keys.data(), cap),
                found);
      for (std::uint32_t i = 0; i < cap; ++i) {
        const std::uint32_t slot = some[i];
        const auto to = static_cast<std::uint32_t>(std::int64_t{from[slot]} + to_offset[slot]);
        ASSERT_EQ(arc_keys[i], (std::uint64_t{from[slot]} << 32) | to) << q << " " << i;
      }
    }
  }
  EXPECT_GT(prefixes, 40);  // the smaller budgets found fewer, not only all or none
}

// A cap on the hits (KdRanking) keeps, in the order found, the hits of the
// lowest rank codes (leaf_scan.h's formula, in every encoding): the largest
// set of whole codes within max_hits, so every kept hit ranks below every
// dropped one; without the cap reached, the uncapped answer.
TYPED_TEST(KdTreeTyped, RankedSearchKeepsTheBestRankedHits) {
  using T = TypeParam;
  using Dist = typename KdTraits<T>::Dist;
  using Point = KdPoint<T, kSearchDims>;
  Rng rng(23);
  const std::uint32_t n = 20000;
  const AttributedTree<T> t = attributed_tree<T>(rng, n);
  const BasicKdTreeView<T, kSearchDims> tree(t.points.data(), nullptr, n, t.nodes.data(), t.depth,
                                             t.bounds.data());
  // Keys that name their slot: from = slot, to = from.
  std::vector<std::uint32_t> from(n);
  for (std::uint32_t i = 0; i < n; ++i) from[i] = i;
  const std::vector<std::int16_t> to_offset(n, 0);
  const KdArcKeys keys{from.data(), to_offset.data()};
  const auto r2 = radius2_of<T>(0.7f);
  const auto box =
      static_cast<Dist>(std::is_same_v<T, float> ? 0.2 : 0.2 * encoding_scale(encoding_of<T>()));
  KdRanking ranking;
  ranking.descriptor = static_cast<float>(256.0 / (5.0 * static_cast<double>(r2)));
  ranking.attribute = static_cast<float>(
      2.0 * 256.0 / (5.0 * (static_cast<double>(box) + 1) * (static_cast<double>(box) + 1)));
  auto code_of = [&](const Point& q, std::uint32_t slot) {
    const Point& p = t.points[slot];
    Dist a2 = 0;
    for (int d = kDescriptorSize; d < kSearchDims; ++d) {
      const Dist e = static_cast<Dist>(p[d]) - static_cast<Dist>(q[d]);
      a2 += e * e;
    }
    const float r = static_cast<float>(kd_distance2(p, q)) * ranking.descriptor +
                    static_cast<float>(a2) * ranking.attribute;
    return r >= 255.f ? 255 : static_cast<int>(r);
  };
  std::vector<std::uint64_t> all(n), kept(n);
  int cut_cases = 0;
  for (int q = 0; q < 40; ++q) {
    const Point query = with_attributes<T>(rng, test::clustered_descriptors(rng, 1)[0]);
    for (int leaves : {1, 8, 24}) {
      ranking.max_hits = 0;
      const std::uint32_t found =
          tree.radius_search_approximate(query, r2, box, leaves, keys, ranking, all.data(), n);
      for (std::uint32_t max_hits : {found + 1, found / 2, found / 5, 1u}) {
        if (max_hits == 0) continue;
        ranking.max_hits = max_hits;
        const std::uint32_t k =
            tree.radius_search_approximate(query, r2, box, leaves, keys, ranking, kept.data(), n);
        ASSERT_LE(k, std::min(found, max_hits)) << q << " " << leaves;
        // A subsequence of the uncapped hits, in order.
        std::uint32_t at = 0;
        int worst_kept = -1;
        for (std::uint32_t i = 0; i < k; ++i) {
          while (at < found && all[at] != kept[i]) ++at;
          ASSERT_LT(at, found) << q << " " << leaves << " " << i;
          worst_kept =
              std::max(worst_kept, code_of(query, static_cast<std::uint32_t>(kept[i] >> 32)));
          ++at;
        }
        // Every dropped hit ranks at or above the first code not kept, and
        // that code's hits would have passed max_hits.
        int best_dropped = 256, at_best = 0;
        for (std::uint32_t i = 0; i < found; ++i) {
          if (std::find(kept.begin(), kept.begin() + k, all[i]) != kept.begin() + k) continue;
          const int c = code_of(query, static_cast<std::uint32_t>(all[i] >> 32));
          if (c < best_dropped) at_best = 0;
          best_dropped = std::min(best_dropped, c);
          at_best += c == best_dropped ? 1 : 0;
        }
        EXPECT_LT(worst_kept, best_dropped) << q << " " << leaves;
        if (k < found) {
          EXPECT_GT(k + static_cast<std::uint32_t>(at_best), max_hits) << q << " " << leaves;
          ++cut_cases;
        } else {
          EXPECT_TRUE(std::equal(kept.begin(), kept.begin() + k, all.begin()));
        }
      }
    }
  }
  EXPECT_GT(cut_cases, 100);  // the cap cut most searches
}

// A walk over every leaf of a deep tree with a radius that keeps every far
// child needs more pending cells than the search holds (512): the surplus
// is dropped, never written past the cells, and what is found stays a
// subset of the exact answer.
TEST(KdTree, ApproximateSearchDropsCellsBeyondItsQueue) {
  using T = std::int8_t;  // the device's trees; the walk is the same template for all
  using Point = KdPoint<T, kSearchDims>;
  Rng rng(21);
  const std::uint32_t n = 1u << 20;
  std::vector<Point> data;
  for (const ArcDescriptor& d : test::clustered_descriptors(rng, n))
    data.push_back(with_attributes<T>(rng, d));
  std::vector<Point> points;
  std::vector<std::uint32_t> ids;
  std::vector<typename KdTraits<T>::Node> nodes;
  build_kdtree<T, kSearchDims>(data.data(), n, points, ids, nodes, 4.0);
  const int depth = kdtree_depth(n);
  const BasicKdTreeView<T, kSearchDims> tree(points.data(), ids.data(), n, nodes.data(), depth);
  const auto r2 = radius2_of<T>(1.9f);  // unit descriptors: nearly every cell may match
  const auto box = std::numeric_limits<typename KdTraits<T>::Dist>::max();
  std::vector<std::uint32_t> a(n), b(n);
  const Point q = with_attributes<T>(rng, test::clustered_descriptors(rng, 1)[0]);
  const std::uint32_t all = tree.radius_search(q, r2, box, a.data(), n);
  ASSERT_GT(all, n / 2);
  const std::uint32_t some = tree.radius_search_approximate(q, r2, box, 1 << depth, b.data(), n);
  EXPECT_LT(some, all);  // cells were dropped
  EXPECT_GT(some, 0u);
  std::sort(a.begin(), a.begin() + all);
  std::sort(b.begin(), b.begin() + some);
  EXPECT_TRUE(std::includes(a.begin(), a.begin() + all, b.begin(), b.begin() + some));
}

TYPED_TEST(KdTreeTyped, KnnEqualsBruteForce) {
  using T = TypeParam;
  using Dist = typename KdTraits<T>::Dist;
  Rng rng(4);
  const auto data = encode_all<T>(test::clustered_descriptors(rng, 5000));
  const Tree<T> t = make_tree<T>(data);
  for (int q = 0; q < 200; ++q) {
    const KdPoint<T> query = encode<T>(test::clustered_descriptors(rng, 1)[0]);
    // Closest first, ties by id: integer distances tie often.
    std::vector<std::pair<Dist, std::uint32_t>> all;
    for (std::uint32_t i = 0; i < data.size(); ++i)
      all.emplace_back(kd_distance2<T>(data[i], query), i);
    std::sort(all.begin(), all.end());
    for (int k : {1, 5, 64}) {
      std::uint32_t ids[64];
      Dist d2[64];
      ASSERT_EQ(t.view.knn_search(query, k, ids, d2), k);
      for (int i = 0; i < k; ++i) {
        EXPECT_EQ(d2[i], all[static_cast<std::size_t>(i)].first) << "k " << k << " rank " << i;
        EXPECT_EQ(ids[i], all[static_cast<std::size_t>(i)].second) << "k " << k << " rank " << i;
      }
    }
  }
  // Fewer points than k.
  const auto few = encode_all<T>(test::clustered_descriptors(rng, 3));
  const Tree<T> small = make_tree<T>(few);
  std::uint32_t ids[64];
  Dist d2[64];
  EXPECT_EQ(small.view.knn_search(few[0], 10, ids, d2), 3);
  EXPECT_EQ(d2[0], Dist{0});
}

TYPED_TEST(KdTreeTyped, RadiusSearchReportsTruncation) {
  using T = TypeParam;
  Rng rng(3);
  const auto data = encode_all<T>(test::clustered_descriptors(rng, 2000));
  const Tree<T> t = make_tree<T>(data);
  std::uint32_t out[5] = {0, 0, 0, 0, 0};
  // Radius 2 covers every unit vector.
  const std::uint32_t found = t.view.radius_search(data[0], radius2_of<T>(2.f), out, 3);
  EXPECT_EQ(found, 2000u);
  EXPECT_EQ(out[3], 0u);  // nothing written past the capacity
  EXPECT_EQ(out[4], 0u);
}

TYPED_TEST(KdTreeTyped, DeterministicBuild) {
  using T = TypeParam;
  Rng a(9), b(9);
  const Tree<T> t1 = make_tree<T>(encode_all<T>(test::clustered_descriptors(a, 3000)));
  const Tree<T> t2 = make_tree<T>(encode_all<T>(test::clustered_descriptors(b, 3000)));
  EXPECT_EQ(t1.ids, t2.ids);
  ASSERT_EQ(t1.nodes.size(), t2.nodes.size());
  for (std::size_t i = 0; i < t1.nodes.size(); ++i) {
    EXPECT_EQ(t1.nodes[i].dim, t2.nodes[i].dim);
    EXPECT_EQ(t1.nodes[i].split, t2.nodes[i].split);
  }
}

TYPED_TEST(KdTreeTyped, QueriesAllocateNothing) {
  using T = TypeParam;
  using Dist = typename KdTraits<T>::Dist;
  Rng rng(5);
  const auto data = encode_all<T>(test::clustered_descriptors(rng, 20000));
  const Tree<T> t = make_tree<T>(data);
  const auto queries = encode_all<T>(test::clustered_descriptors(rng, 50));
  std::vector<std::uint32_t> out(1000);
  std::uint32_t ids[64];
  Dist d2[64];
  const auto r2 = radius2_of<T>(0.3f);
  std::uint64_t found = 0;
  test::AllocationCounter allocations;
  for (const KdPoint<T>& q : queries) {
    found += t.view.radius_search(q, r2, out.data(), static_cast<std::uint32_t>(out.size()));
    found += static_cast<std::uint64_t>(t.view.knn_search(q, 64, ids, d2));
  }
  EXPECT_EQ(allocations.count(), 0);
  EXPECT_GT(found, 0u);
}

// Opposite extreme points: the largest squared distances the domain holds,
// computed without overflow.
TYPED_TEST(KdTreeTyped, ExtremeDistancesDoNotOverflow) {
  using T = TypeParam;
  using Dist = typename KdTraits<T>::Dist;
  if constexpr (!std::is_same_v<T, float>) {
    constexpr T hi = std::numeric_limits<T>::max();
    std::vector<KdPoint<T>> data(100);
    for (std::size_t i = 0; i < data.size(); ++i)
      data[i].fill(static_cast<T>(i % 2 == 0 ? hi : -hi));
    const Tree<T> t = make_tree<T>(data);
    KdPoint<T> q;
    q.fill(hi);
    std::uint32_t ids[64];
    Dist d2[64];
    ASSERT_EQ(t.view.knn_search(q, 64, ids, d2), 64);
    const Dist far = static_cast<Dist>(kDescriptorSize) * (2 * static_cast<Dist>(hi)) *
                     (2 * static_cast<Dist>(hi));
    EXPECT_EQ(d2[0], 0);
    EXPECT_EQ(d2[63], far);
    std::vector<std::uint32_t> out(100);
    EXPECT_EQ(t.view.radius_search(q, std::numeric_limits<Dist>::max(), out.data(), 100), 100u);
    EXPECT_EQ(t.view.radius_search(q, far, out.data(), 100), 50u);
  }
}

// The vectorised leaf scan (NEON or SSE2, whichever this build targets)
// gives exactly the scalar reference's hits, extremes included.
TEST(LeafScan, VectorisedEqualsScalar) {
  std::printf("leaf scan: %s\n", leaf_scan_isa());
  Rng rng(11);
  auto random_point = [&](int spread) {
    ArcSearchPointI8 p;
    for (auto& v : p)
      v = static_cast<std::int8_t>(static_cast<int>(rng.uniform(2 * spread + 1)) - spread);
    return p;
  };
  std::vector<ArcSearchPointI8> points(kLeafSize);
  std::uint16_t a[kLeafSize], b[kLeafSize];
  long total = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const int spread = trial % 4 == 0 ? 127 : 40;
    for (auto& p : points) p = random_point(spread);
    const ArcSearchPointI8 q = random_point(spread);
    const int n = 1 + static_cast<int>(rng.uniform(kLeafSize));  // odd and even sizes
    const std::int32_t radius2 = static_cast<std::int32_t>(rng.uniform(6 * 254 * 254 + 2));
    const std::int32_t box = trial % 5 == 0 ? std::numeric_limits<std::int32_t>::max()
                                            : static_cast<std::int32_t>(rng.uniform(256));
    const int ns = scan_leaf_i8_scalar(points.data(), n, q, radius2, box, a);
    const int nv = scan_leaf_i8(points.data(), n, q, radius2, box, b);
    ASSERT_EQ(ns, nv) << "trial " << trial;
    for (int i = 0; i < ns; ++i) ASSERT_EQ(a[i], b[i]) << "trial " << trial;
    total += ns;
  }
  EXPECT_GT(total, 10000);  // the cases were not all empty
}

// The ranked scan finds what the plain scan finds, and its rank codes are
// the scalar reference's, in every lane (the vector code computes them in
// float as leaf_rank_code() does).
TEST(LeafScan, RankedVectorisedEqualsScalar) {
  Rng rng(13);
  auto random_point = [&](int spread) {
    ArcSearchPointI8 p;
    for (auto& v : p)
      v = static_cast<std::int8_t>(static_cast<int>(rng.uniform(2 * spread + 1)) - spread);
    return p;
  };
  std::vector<ArcSearchPointI8> points(kLeafSize);
  std::uint16_t plain[kLeafSize], a[kLeafSize], b[kLeafSize];
  std::uint8_t ra[kLeafSize], rb[kLeafSize];
  long total = 0;
  int codes_seen[256] = {};
  for (int trial = 0; trial < 4000; ++trial) {
    const int spread = trial % 4 == 0 ? 127 : 40;
    for (auto& p : points) p = random_point(spread);
    const ArcSearchPointI8 q = random_point(spread);
    const int n = 1 + static_cast<int>(rng.uniform(kLeafSize));
    const std::int32_t radius2 = static_cast<std::int32_t>(rng.uniform(6 * 254 * 254 + 2));
    const std::int32_t box = trial % 5 == 0 ? std::numeric_limits<std::int32_t>::max()
                                            : static_cast<std::int32_t>(rng.uniform(256));
    const LeafRankWeights w{static_cast<float>(256.0 / (1.0 + radius2 * rng.uniform01())),
                            static_cast<float>(rng.uniform01() * 0.05)};
    const int np = scan_leaf_i8(points.data(), n, q, radius2, box, plain);
    const int ns = scan_leaf_i8_ranked_scalar(points.data(), n, q, radius2, box, w, a, ra);
    const int nv = scan_leaf_i8_ranked(points.data(), n, q, radius2, box, w, b, rb);
    ASSERT_EQ(ns, np) << "trial " << trial;
    ASSERT_EQ(ns, nv) << "trial " << trial;
    for (int i = 0; i < ns; ++i) {
      ASSERT_EQ(a[i], plain[i]) << "trial " << trial;
      ASSERT_EQ(a[i], b[i]) << "trial " << trial;
    }
    for (int i = 0; i < n; ++i) {
      std::int32_t d2 = 0, a2 = 0;
      for (int c = 0; c < kSearchDims; ++c) {
        const std::int32_t d = std::int32_t{points[i][c]} - std::int32_t{q[c]};
        (c < kDescriptorSize ? d2 : a2) += d * d;
      }
      ASSERT_EQ(ra[i], leaf_rank_code(d2, a2, w)) << "trial " << trial << " point " << i;
      ASSERT_EQ(ra[i], rb[i]) << "trial " << trial << " point " << i;
      ++codes_seen[ra[i]];
    }
    total += ns;
  }
  EXPECT_GT(total, 10000);
  int distinct = 0;
  for (int c : codes_seen) distinct += c > 0 ? 1 : 0;
  EXPECT_GT(distinct, 200);  // codes across the range, not all saturated
}

TEST(LeafScan, VectorisedBoundsTestEqualsScalar) {
  Rng rng(12);
  auto component = [&](int spread) {
    return static_cast<int>(rng.uniform(2 * spread + 1)) - spread;
  };
  long may = 0, may_not = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const int spread = trial % 4 == 0 ? 127 : 40;
    ArcSearchPointI8 bounds[2], q;
    for (int c = 0; c < kSearchDims; ++c) {
      int lo = component(spread), hi = component(spread);
      // Mostly valid boxes, sometimes empty ones (minimum above maximum).
      if (trial % 7 != 0 && lo > hi) std::swap(lo, hi);
      bounds[0][c] = static_cast<std::int8_t>(lo);
      bounds[1][c] = static_cast<std::int8_t>(hi);
      q[c] = static_cast<std::int8_t>(component(spread));
    }
    const std::int32_t radius2 = static_cast<std::int32_t>(rng.uniform(4 * 80 * 80 + 2));
    const std::int32_t box = trial % 5 == 0 ? std::numeric_limits<std::int32_t>::max()
                                            : static_cast<std::int32_t>(rng.uniform(64));
    const bool s = leaf_may_match_i8_scalar(bounds, q, radius2, box);
    ASSERT_EQ(s, leaf_may_match_i8(bounds, q, radius2, box)) << "trial " << trial;
    (s ? may : may_not) += 1;
  }
  // Both answers were exercised.
  EXPECT_GT(may, 2000);
  EXPECT_GT(may_not, 2000);
}

TEST(LeafScan, BoundsTestNeverRejectsAMatch) {
  // A leaf's bounds hold its points, so any point the scan finds must pass.
  Rng rng(13);
  std::vector<ArcSearchPointI8> points(kLeafSize);
  std::uint16_t hits[kLeafSize];
  long checked = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    ArcSearchPointI8 bounds[2], q;
    bounds[0].fill(127);
    bounds[1].fill(-128);
    for (auto& p : points) {
      for (int c = 0; c < kSearchDims; ++c) {
        p[c] = static_cast<std::int8_t>(static_cast<int>(rng.uniform(81)) - 40);
        bounds[0][c] = std::min(bounds[0][c], p[c]);
        bounds[1][c] = std::max(bounds[1][c], p[c]);
      }
    }
    for (auto& v : q) v = static_cast<std::int8_t>(static_cast<int>(rng.uniform(121)) - 60);
    const std::int32_t radius2 = static_cast<std::int32_t>(rng.uniform(3 * 40 * 40));
    const std::int32_t box = static_cast<std::int32_t>(rng.uniform(40));
    const int n = scan_leaf_i8(points.data(), kLeafSize, q, radius2, box, hits);
    if (n > 0) {
      ++checked;
      ASSERT_TRUE(leaf_may_match_i8(bounds, q, radius2, box)) << "trial " << trial;
    }
  }
  EXPECT_GT(checked, 100);
}

TEST(DescriptorEncoding, QuantiseRoundsAndSaturates) {
  EXPECT_EQ(quantise_component<std::int8_t>(1.f), 127);
  EXPECT_EQ(quantise_component<std::int8_t>(-1.f), -127);
  EXPECT_EQ(quantise_component<std::int8_t>(0.f), 0);
  EXPECT_EQ(quantise_component<std::int8_t>(0.5f), 64);  // 63.5: half away from zero
  EXPECT_EQ(quantise_component<std::int8_t>(-0.5f), -64);
  EXPECT_EQ(quantise_component<std::int8_t>(0.49f / 127.f), 0);
  EXPECT_EQ(quantise_component<std::int8_t>(0.3f), 38);  // 38.1
  EXPECT_EQ(quantise_component<std::int8_t>(5.f), 127);
  EXPECT_EQ(quantise_component<std::int8_t>(-5.f), -127);  // never -128
  EXPECT_EQ(quantise_component<std::int8_t>(std::nanf("")), 0);
  EXPECT_EQ(quantise_component<std::int16_t>(1.f), 32767);
  EXPECT_EQ(quantise_component<std::int16_t>(-1.f), -32767);
  EXPECT_EQ(quantise_component<std::int16_t>(0.3f), 9830);  // 9830.1
  EXPECT_EQ(quantise_component<std::int16_t>(-std::numeric_limits<float>::infinity()), -32767);
  const ArcDescriptor d = {0.5f, -0.5f, 0.25f, 0.f, 1.f, -1.f};
  EXPECT_EQ(quantise<std::int8_t>(d), (ArcDescriptorI8{64, -64, 32, 0, 127, -127}));
  EXPECT_EQ(quantise<std::int16_t>(d), (ArcDescriptorI16{16384, -16384, 8192, 0, 32767, -32767}));
}

TEST(DescriptorEncoding, ScaledRadiusIsExactCeiling) {
  std::int64_t r2 = 0;
  const std::int64_t i32 = std::numeric_limits<std::int32_t>::max();
  const std::int64_t i64 = std::numeric_limits<std::int64_t>::max();
  // 0.3f^2 = 0.0900000035...; * 127^2 = 1451.61... -> 1452.
  ASSERT_TRUE(scaled_radius2(0.3f, DescriptorEncoding::kInt8, i32, r2));
  EXPECT_EQ(r2, 1452);
  // Exactly representable: 0.5^2 * 127^2 = 4032.25 -> 4033; 1^2 * 127^2 stays 16129.
  ASSERT_TRUE(scaled_radius2(0.5f, DescriptorEncoding::kInt8, i32, r2));
  EXPECT_EQ(r2, 4033);
  ASSERT_TRUE(scaled_radius2(1.f, DescriptorEncoding::kInt8, i32, r2));
  EXPECT_EQ(r2, 16129);
  ASSERT_TRUE(scaled_radius2(1.f, DescriptorEncoding::kInt16, i64, r2));
  EXPECT_EQ(r2, 32767LL * 32767LL);
  // For every threshold: d < r2 exactly when d / scale^2 < threshold^2 (in
  // exact arithmetic; long double holds these products exactly on x86-64,
  // double nearly so elsewhere).
  for (float t : {0.05f, 0.2f, 0.3f, 0.45f, 0.7f, 1.3f, 2.f}) {
    for (DescriptorEncoding e : {DescriptorEncoding::kInt8, DescriptorEncoding::kInt16}) {
      ASSERT_TRUE(scaled_radius2(t, e, i64, r2)) << t;
      const long double s = encoding_scale(e);
      const long double exact = static_cast<long double>(t * t) * s * s;
      EXPECT_GE(static_cast<long double>(r2), exact) << t;
      EXPECT_LT(static_cast<long double>(r2 - 1), exact) << t;
    }
  }
  // Overflow of the search type and bad radii are refused.
  EXPECT_FALSE(scaled_radius2(2.f, DescriptorEncoding::kInt16, i32, r2));  // 4.29e9
  EXPECT_TRUE(scaled_radius2(2.f, DescriptorEncoding::kInt16, i64, r2));
  EXPECT_FALSE(scaled_radius2(1e30f, DescriptorEncoding::kInt8, i64, r2));
  EXPECT_FALSE(scaled_radius2(0.f, DescriptorEncoding::kInt8, i32, r2));
  EXPECT_FALSE(scaled_radius2(-1.f, DescriptorEncoding::kInt8, i32, r2));
  EXPECT_FALSE(scaled_radius2(std::nanf(""), DescriptorEncoding::kInt8, i32, r2));
  EXPECT_FALSE(
      scaled_radius2(std::numeric_limits<float>::infinity(), DescriptorEncoding::kInt8, i32, r2));
}

// Quantised search against the float reference on the same descriptors: the
// integer domains find nearly the same neighbours (the small difference is
// rounding at the radius), which is what lets int8 replace float32.
TEST(DescriptorEncoding, QuantisedSearchAgreesWithFloat) {
  Rng rng(7);
  // Queries from the same clusters as the data.
  auto data = test::clustered_descriptors(rng, 20200);
  const std::vector<ArcDescriptor> queries(data.end() - 200, data.end());
  data.resize(20000);
  const Tree<float> f = make_tree<float>(data);
  const Tree<std::int16_t> s = make_tree<std::int16_t>(encode_all<std::int16_t>(data));
  const Tree<std::int8_t> b = make_tree<std::int8_t>(encode_all<std::int8_t>(data));
  std::vector<std::uint32_t> out(data.size());
  const auto cap = static_cast<std::uint32_t>(out.size());
  auto ids = [&](std::uint32_t n) {
    std::vector<std::uint32_t> v(out.begin(), out.begin() + n);
    std::sort(v.begin(), v.end());
    return v;
  };
  auto overlap = [](const std::vector<std::uint32_t>& a, const std::vector<std::uint32_t>& c) {
    std::vector<std::uint32_t> both;
    std::set_intersection(a.begin(), a.end(), c.begin(), c.end(), std::back_inserter(both));
    return both.size();
  };
  std::size_t total = 0, same16 = 0, same8 = 0, got16 = 0, got8 = 0;
  for (const ArcDescriptor& query : queries) {
    const auto reference = ids(f.view.radius_search(query, 0.3f * 0.3f, out.data(), cap));
    const auto r16 = ids(s.view.radius_search(quantise<std::int16_t>(query),
                                              radius2_of<std::int16_t>(0.3f), out.data(), cap));
    const auto r8 = ids(b.view.radius_search(quantise<std::int8_t>(query),
                                             radius2_of<std::int8_t>(0.3f), out.data(), cap));
    total += reference.size();
    got16 += r16.size();
    got8 += r8.size();
    same16 += overlap(reference, r16);
    same8 += overlap(reference, r8);
  }
  ASSERT_GT(total, 10000u);
  // int16: rounding of 1/65534 per component; int8: 1/254.
  EXPECT_GE(same16, total - total / 1000);
  EXPECT_LE(got16 - same16, total / 1000);
  EXPECT_GE(same8, total - total / 50);
  EXPECT_LE(got8 - same8, total / 50);
  std::printf(
      "radius 0.3 over 200 queries: float32 %zu, int16 %zu (%zu shared), int8 %zu (%zu shared)\n",
      total, got16, same16, got8, same8);
}

}  // namespace
}  // namespace kg
