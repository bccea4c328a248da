// Arc descriptors for the search-tree comparisons (tests/unit/
// test_kdtree_flann.cpp, tests/bench/bench_search.cpp): unit-norm 6-D
// vectors clustered like real ones around a few dense directions, as
// tests/core/test_kdtree.cpp makes them; the flat kd-tree over them; brute
// force; and the same points as a FLANN matrix.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/description/arc_types.h"
#include "core/index/kdtree.h"
#include "core/support/rng.h"
#include "keygraph/types.h"

namespace kg::test {

// n unit descriptors around `clusters` random centres (each component of a
// centre uniform in [-1, 1], then +-0.3 uniform noise, then normalised).
inline std::vector<ArcDescriptor> clustered_descriptors(Rng& rng, std::uint32_t n,
                                                        int clusters = 20) {
  std::vector<ArcDescriptor> centres(static_cast<std::size_t>(clusters));
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

// The flat kd-tree over `data` (tree order plus the id of each slot).
struct FlatTree {
  std::vector<ArcDescriptor> points;
  std::vector<std::uint32_t> ids;
  std::vector<KdNode> nodes;
  KdTreeView view;
};

inline void build_flat_tree(const std::vector<ArcDescriptor>& data, FlatTree& t) {
  const auto n = static_cast<std::uint32_t>(data.size());
  build_kdtree(data.data(), n, t.points, t.ids, t.nodes);
  t.view = KdTreeView(t.points.data(), t.ids.data(), n, t.nodes.data(), kdtree_depth(n));
}

// Squared Euclidean distance summed in component order (the flat tree's
// arithmetic for float points).
inline float distance2(const ArcDescriptor& a, const ArcDescriptor& b) {
  float s = 0.f;
  for (int i = 0; i < kDescriptorSize; ++i) {
    const float d = a[i] - b[i];
    s += d * d;
  }
  return s;
}

// Brute force: ids of the points with distance2 < radius2, ascending.
inline void brute_radius(const std::vector<ArcDescriptor>& data, const ArcDescriptor& q,
                         float radius2, std::vector<std::uint32_t>& out) {
  out.clear();
  for (std::uint32_t i = 0; i < data.size(); ++i) {
    if (distance2(data[i], q) < radius2) out.push_back(i);
  }
}

// Brute force: the k nearest (squared distance, id), closest first, ties by id.
inline void brute_knn(const std::vector<ArcDescriptor>& data, const ArcDescriptor& q, int k,
                      std::vector<std::pair<float, std::uint32_t>>& out) {
  out.clear();
  out.reserve(data.size());
  for (std::uint32_t i = 0; i < data.size(); ++i) out.emplace_back(distance2(data[i], q), i);
  const auto kk = std::min<std::size_t>(static_cast<std::size_t>(k), out.size());
  std::partial_sort(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(kk), out.end());
  out.resize(kk);
}

}  // namespace kg::test
