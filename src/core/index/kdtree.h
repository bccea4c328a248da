// Flat kd-tree over arc descriptors, laid out so it can live in a file and
// be used in place (zero copy):
// - points: N points of D components of type T (float, int16_t or int8_t:
//   DescriptorParams::encoding), in tree order. The first kDescriptorSize
//   components are an arc descriptor, compared by Euclidean distance; the
//   model index adds kArcAttributes more (D = kSearchDims: the arc's scale
//   attributes), which a radius query matches by a box instead: each within
//   `box` of the query's;
// - ids (optional): for each tree slot, the original index of its point.
//   The model index stores its arcs in tree order instead, so it has none
//   and a query returns tree slots;
// - nodes: the 2^L - 1 internal nodes of a complete binary tree in
//   breadth-first order (children of node i are 2i+1 and 2i+2), each a split
//   dimension and value in the points' domain. Node ranges are implicit: the
//   root covers [0, N) and a node covering [b, e) gives [b, m) to its left
//   and [m, e) to its right child with m = b + (e - b) / 2. L is the smallest
//   depth whose leaves hold at most kLeafSize points. Left points have
//   value <= split <= right points.
// Distances are squared Euclidean over the descriptor components, in the
// points' domain: float for float points, int32 for int8 (at most
// 6 * 254^2), int64 for int16 (6 * 65534^2 does not fit in 32 bits).
// Queries use a fixed-size stack and allocate nothing.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/description/arc_types.h"
#include "keygraph/types.h"

namespace kg {

// Internal node of a float32 tree (8 bytes in the file).
struct KdNode {
  float split = 0.f;
  std::uint32_t dim = 0;
};

// Internal node of an int16 or int8 tree (4 bytes in the file).
struct KdNodeInt {
  std::int16_t split = 0;
  std::uint16_t dim = 0;
};

template <class T>
struct KdTraits;
// Offset: a difference of two components (int8: within +-254), kept per
// dimension by a search; small so search frames are cheap to copy.
template <>
struct KdTraits<float> {
  using Node = KdNode;
  using Dist = float;
  using Offset = float;
};
template <>
struct KdTraits<std::int16_t> {
  using Node = KdNodeInt;
  using Dist = std::int64_t;
  using Offset = std::int32_t;
};
template <>
struct KdTraits<std::int8_t> {
  using Node = KdNodeInt;
  using Dist = std::int32_t;
  using Offset = std::int16_t;
};

template <class T, std::size_t D = kDescriptorSize>
using KdPoint = std::array<T, D>;

// Squared Euclidean distance of the descriptor components in the points'
// domain (for float, the same arithmetic as squared_distance() in
// core/description/arc_descriptor.h).
template <class T, std::size_t D>
inline typename KdTraits<T>::Dist kd_distance2(const std::array<T, D>& p,
                                               const std::array<T, D>& q) {
  using Dist = typename KdTraits<T>::Dist;
  Dist s = 0;
  for (int i = 0; i < kDescriptorSize; ++i) {
    const Dist d = static_cast<Dist>(p[i]) - static_cast<Dist>(q[i]);
    s += d * d;
  }
  return s;
}

// Points per leaf, at most (index format 5; 4.x: 32). An approximate
// search's cost is walking to leaves plus scanning them: with 64, 20 leaves
// scan more arcs than 32 leaves of 32 for less than half the walking, and
// find as many of the right ones (docs/RUNTIME.md).
inline constexpr int kLeafSize = 64;
inline constexpr int kMaxTreeDepth = 40;

// Depth L of the tree for n points (0 when n <= kLeafSize).
int kdtree_depth(std::uint32_t n);

// Builds a tree over points[0..n): fills `points` (tree order), `ids` (the
// source index of each tree slot) and `nodes` (resized). Each node splits
// the dimension of largest spread, the attributes' spreads multiplied by
// `attribute_weight` (the ratio of the descriptor radius to the box
// half-width, so that both are cut alike). Deterministic: ties are broken by
// source index.
template <class T, std::size_t D = kDescriptorSize>
void build_kdtree(const KdPoint<T, D>* source, std::uint32_t n, std::vector<KdPoint<T, D>>& points,
                  std::vector<std::uint32_t>& ids, std::vector<typename KdTraits<T>::Node>& nodes,
                  double attribute_weight = 1.0);

// The model index's arcs by tree slot (ModelIndex::arc(): from, and to as
// an offset from it): given these, an approximate search writes each hit's
// arc key (from << 32 | to) where it would write its slot, so a look-up
// reads the arcs of a leaf while the leaf is in the cache instead of
// storing slots and converting them one by one afterwards.
struct KdArcKeys {
  const std::uint32_t* from = nullptr;
  const std::int16_t* to_offset = nullptr;
};

// A cap on an approximate search's hits (the keys search): at most
// max_hits of them, those of the lowest rank codes (core/index/leaf_scan.h:
// the squared descriptor distance times `descriptor` plus the attributes'
// squared differences times `attribute`, in 256 steps; within a step the
// first found), in the order found. max_hits 0: every hit. Applies to
// budgets of up to 64 leaves (BasicKdTreeView's bounded queue); larger
// budgets return every hit.
struct KdRanking {
  std::uint32_t max_hits = 0;
  float descriptor = 0.f;
  float attribute = 0.f;
};

template <class T, std::size_t D = kDescriptorSize>
class BasicKdTreeView {
 public:
  using Point = KdPoint<T, D>;
  using Node = typename KdTraits<T>::Node;
  using Dist = typename KdTraits<T>::Dist;

  BasicKdTreeView() = default;
  // `ids` may be null: queries then report tree slots.
  // `leaf_bounds` (optional): per leaf, left to right, the component-wise
  // minimum then maximum of its points (kdtree_leaf_bounds()); a radius
  // query skips leaves whose box cannot hold a match.
  BasicKdTreeView(const Point* points, const std::uint32_t* ids, std::uint32_t n, const Node* nodes,
                  int depth, const Point* leaf_bounds = nullptr)
      : points_(points), ids_(ids), n_(n), nodes_(nodes), depth_(depth), bounds_(leaf_bounds) {}

  std::uint32_t size() const { return n_; }

  // Ids of all points with squared distance < radius2 from q and every
  // attribute within `box` of q's (|p_d - q_d| <= box; no attribute check
  // without `box`). Writes at most `capacity` ids to `out` and returns how
  // many points matched in total (a return value > capacity means the
  // output was truncated).
  std::uint32_t radius_search(const Point& q, Dist radius2, std::uint32_t* out,
                              std::uint32_t capacity) const;
  std::uint32_t radius_search(const Point& q, Dist radius2, Dist box, std::uint32_t* out,
                              std::uint32_t capacity) const;
  // The same, approximately: leaves in order of their distance bound (best
  // bin first), at most `max_leaves` of them. Finds a subset of the exact
  // answer, the points in the leaves nearest the query first.
  std::uint32_t radius_search_approximate(const Point& q, Dist radius2, Dist box, int max_leaves,
                                          std::uint32_t* out, std::uint32_t capacity) const;
  // The same, writing the arc keys of the hits (`keys` by slot) instead of
  // their slots: out[i] = from << 32 | to of the i-th slot found.
  std::uint32_t radius_search_approximate(const Point& q, Dist radius2, Dist box, int max_leaves,
                                          const KdArcKeys& keys, std::uint64_t* out,
                                          std::uint32_t capacity) const;
  // The same, keeping only the best ranked hits (`ranking`); returns how
  // many were kept (at most ranking.max_hits when it is not 0) when all
  // hits fitted in `capacity`, else the hits found.
  std::uint32_t radius_search_approximate(const Point& q, Dist radius2, Dist box, int max_leaves,
                                          const KdArcKeys& keys, const KdRanking& ranking,
                                          std::uint64_t* out, std::uint32_t capacity) const;

  // The k (<= 64) nearest points by descriptor distance (attributes are not
  // compared), closest first (ties: smaller id first): ids and squared
  // distances. Returns the number written (min(k, size())).
  int knn_search(const Point& q, int k, std::uint32_t* ids, Dist* dist2) const;

 private:
  std::uint32_t id(std::uint32_t slot) const { return ids_ != nullptr ? ids_[slot] : slot; }
  // Asks the cache for the bounds and points of the leaf `node`, slots
  // [begin, end).
  void prefetch_leaf(std::uint32_t node, std::uint32_t begin, std::uint32_t end) const;
  // Appends to out (up to capacity; `found` counts all) the points of the
  // leaf `node`, slots [begin, end), within radius2 and box of q; skips the
  // leaf when its bounds rule it out. `Out` (kdtree.cpp) turns a slot into
  // what is written: its id, or its arc key.
  // A ranked search's hits before its cut: the rank code of each hit
  // written (by its position in the output), and the hits per code.
  struct RankedHits {
    std::uint8_t* ranks;
    std::uint16_t count[256];
    float descriptor, attribute;  // KdRanking's weights
  };
  // With `ranked` not null, also notes each hit's rank code there.
  template <class Out>
  void scan_leaf(std::uint32_t node, std::uint32_t begin, std::uint32_t end, const Point& q,
                 Dist radius2, Dist box, const Out& out, std::uint32_t capacity,
                 std::uint32_t& found, RankedHits* ranked = nullptr) const;
  template <class Out>
  std::uint32_t approximate(const Point& q, Dist radius2, Dist box, int max_leaves, const Out& out,
                            std::uint32_t capacity, const KdRanking* ranking = nullptr) const;

  const Point* points_ = nullptr;
  const std::uint32_t* ids_ = nullptr;
  std::uint32_t n_ = 0;
  const Node* nodes_ = nullptr;
  int depth_ = 0;
  const Point* bounds_ = nullptr;
};

// The leaf bounds of a tree over points[0..n) (tree order) of depth
// kdtree_depth(n): 2 * 2^depth points, per leaf its minimum and maximum per
// component (an empty leaf gets minimum > maximum, never matching).
template <class T, std::size_t D>
void kdtree_leaf_bounds(const KdPoint<T, D>* points, std::uint32_t n,
                        std::vector<KdPoint<T, D>>& out);

using KdTreeView = BasicKdTreeView<float>;
using KdTreeView16 = BasicKdTreeView<std::int16_t>;
using KdTreeView8 = BasicKdTreeView<std::int8_t>;
// The model index's trees: descriptor plus scale attributes.
using ArcTreeView = BasicKdTreeView<float, kSearchDims>;
using ArcTreeView16 = BasicKdTreeView<std::int16_t, kSearchDims>;
using ArcTreeView8 = BasicKdTreeView<std::int8_t, kSearchDims>;

extern template class BasicKdTreeView<float>;
extern template class BasicKdTreeView<std::int16_t>;
extern template class BasicKdTreeView<std::int8_t>;
extern template class BasicKdTreeView<float, kSearchDims>;
extern template class BasicKdTreeView<std::int16_t, kSearchDims>;
extern template class BasicKdTreeView<std::int8_t, kSearchDims>;

}  // namespace kg
