// Flat kd-tree over arc descriptors, laid out so it can live in a file and
// be used in place (zero copy):
// - points: N descriptors of kDescriptorSize floats, in tree order;
// - ids: for each tree slot, the original index (model arc id);
// - nodes: the 2^L - 1 internal nodes of a complete binary tree in
//   breadth-first order (children of node i are 2i+1 and 2i+2), each a split
//   dimension and value. Node ranges are implicit: the root covers [0, N) and
//   a node covering [b, e) gives [b, m) to its left and [m, e) to its right
//   child with m = b + (e - b) / 2. L is the smallest depth whose leaves hold
//   at most kLeafSize points. Left points have value <= split <= right points.
// Queries use a fixed-size stack and allocate nothing.
#pragma once

#include <cstdint>
#include <vector>

#include "keygraph/types.h"

namespace kg {

struct KdNode {
  float split = 0.f;
  std::uint32_t dim = 0;
};

inline constexpr int kLeafSize = 32;
inline constexpr int kMaxTreeDepth = 40;

// Depth L of the tree for n points (0 when n <= kLeafSize).
int kdtree_depth(std::uint32_t n);

// Builds a tree over descriptors[0..n): fills points (tree order), ids and
// nodes (resized). Deterministic.
void build_kdtree(const ArcDescriptor* descriptors, std::uint32_t n,
                  std::vector<ArcDescriptor>& points, std::vector<std::uint32_t>& ids,
                  std::vector<KdNode>& nodes);

class KdTreeView {
 public:
  KdTreeView() = default;
  KdTreeView(const ArcDescriptor* points, const std::uint32_t* ids, std::uint32_t n,
             const KdNode* nodes, int depth)
      : points_(points), ids_(ids), n_(n), nodes_(nodes), depth_(depth) {}

  std::uint32_t size() const { return n_; }

  // Ids of all points with squared distance < radius2 from q. Writes at most
  // `capacity` ids to `out` and returns how many points matched in total
  // (a return value > capacity means the output was truncated).
  std::uint32_t radius_search(const ArcDescriptor& q, float radius2, std::uint32_t* out,
                              std::uint32_t capacity) const;

  // The k (<= 64) nearest points, closest first: ids and squared distances.
  // Returns the number written (min(k, size())).
  int knn_search(const ArcDescriptor& q, int k, std::uint32_t* ids, float* dist2) const;

 private:
  const ArcDescriptor* points_ = nullptr;
  const std::uint32_t* ids_ = nullptr;
  std::uint32_t n_ = 0;
  const KdNode* nodes_ = nullptr;
  int depth_ = 0;
};

}  // namespace kg
