// Flat kd-tree over arc descriptors: exact radius and k-nearest search.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/arc_descriptor.h"
#include "core/kdtree.h"
#include "core/rng.h"

namespace kg {
namespace {

// Unit-norm descriptors clustered like real ones (a few dense directions).
std::vector<ArcDescriptor> random_descriptors(Rng& rng, std::uint32_t n) {
  std::vector<ArcDescriptor> centres(20);
  for (auto& c : centres) {
    for (float& v : c) v = static_cast<float>(rng.uniform01() * 2.0 - 1.0);
  }
  std::vector<ArcDescriptor> out(n);
  for (auto& d : out) {
    const ArcDescriptor& c = centres[rng.uniform(static_cast<std::uint32_t>(centres.size()))];
    float norm = 0.f;
    for (int i = 0; i < kDescriptorSize; ++i) {
      d[i] = c[i] + static_cast<float>(rng.uniform01() - 0.5) * 0.6f;
      norm += d[i] * d[i];
    }
    for (float& v : d) v /= std::sqrt(norm);
  }
  return out;
}

struct Tree {
  std::vector<ArcDescriptor> points;
  std::vector<std::uint32_t> ids;
  std::vector<KdNode> nodes;
  KdTreeView view;
};

Tree make_tree(const std::vector<ArcDescriptor>& data) {
  Tree t;
  const auto n = static_cast<std::uint32_t>(data.size());
  build_kdtree(data.data(), n, t.points, t.ids, t.nodes);
  t.view = KdTreeView(t.points.data(), t.ids.data(), n, t.nodes.data(), kdtree_depth(n));
  return t;
}

TEST(KdTree, LayoutIsCompleteAndAPermutation) {
  Rng rng(1);
  for (std::uint32_t n : {0u, 1u, 7u, 8u, 9u, 100u, 1000u, 4097u}) {
    const auto data = random_descriptors(rng, n);
    const Tree t = make_tree(data);
    EXPECT_EQ(t.nodes.size(), (std::size_t{1} << kdtree_depth(n)) - 1);
    std::vector<std::uint32_t> sorted = t.ids;
    std::sort(sorted.begin(), sorted.end());
    for (std::uint32_t i = 0; i < n; ++i) {
      ASSERT_EQ(sorted[i], i);
      EXPECT_EQ(t.points[i], data[t.ids[i]]);
    }
  }
}

TEST(KdTree, RadiusSearchEqualsBruteForce) {
  Rng rng(2);
  for (std::uint32_t n : {1u, 50u, 3000u, 20000u}) {
    const auto data = random_descriptors(rng, n);
    const Tree t = make_tree(data);
    std::vector<std::uint32_t> out(n + 1);
    for (int q = 0; q < 100; ++q) {
      const ArcDescriptor query = random_descriptors(rng, 1)[0];
      for (float r : {0.1f, 0.3f, 0.5f}) {
        std::vector<std::uint32_t> expected;
        for (std::uint32_t i = 0; i < n; ++i) {
          if (squared_distance(data[i], query) < r * r) expected.push_back(i);
        }
        const std::uint32_t found =
            t.view.radius_search(query, r * r, out.data(), static_cast<std::uint32_t>(out.size()));
        std::vector<std::uint32_t> got(out.begin(), out.begin() + found);
        std::sort(got.begin(), got.end());
        EXPECT_EQ(got, expected) << "n " << n << " r " << r;
      }
    }
  }
}

TEST(KdTree, RadiusSearchReportsTruncation) {
  Rng rng(3);
  const auto data = random_descriptors(rng, 2000);
  const Tree t = make_tree(data);
  std::uint32_t out[5] = {0, 0, 0, 0, 0};
  const std::uint32_t found = t.view.radius_search(data[0], 4.f, out, 3);  // everything matches
  EXPECT_EQ(found, 2000u);
  EXPECT_EQ(out[3], 0u);  // nothing written past the capacity
  EXPECT_EQ(out[4], 0u);
}

TEST(KdTree, KnnEqualsBruteForce) {
  Rng rng(4);
  const auto data = random_descriptors(rng, 5000);
  const Tree t = make_tree(data);
  for (int q = 0; q < 200; ++q) {
    const ArcDescriptor query = random_descriptors(rng, 1)[0];
    std::vector<std::pair<float, std::uint32_t>> all;
    for (std::uint32_t i = 0; i < data.size(); ++i)
      all.emplace_back(squared_distance(data[i], query), i);
    std::sort(all.begin(), all.end());
    for (int k : {1, 5, 64}) {
      std::uint32_t ids[64];
      float d2[64];
      ASSERT_EQ(t.view.knn_search(query, k, ids, d2), k);
      for (int i = 0; i < k; ++i) {
        EXPECT_FLOAT_EQ(d2[i], all[i].first);
        EXPECT_EQ(ids[i], all[i].second);
      }
    }
  }
}

TEST(KdTree, DeterministicBuild) {
  Rng a(9), b(9);
  const auto data = random_descriptors(a, 3000);
  const Tree t1 = make_tree(data), t2 = make_tree(random_descriptors(b, 3000));
  EXPECT_EQ(t1.ids, t2.ids);
  ASSERT_EQ(t1.nodes.size(), t2.nodes.size());
  for (std::size_t i = 0; i < t1.nodes.size(); ++i) {
    EXPECT_EQ(t1.nodes[i].dim, t2.nodes[i].dim);
    EXPECT_EQ(t1.nodes[i].split, t2.nodes[i].split);
  }
}

}  // namespace
}  // namespace kg
