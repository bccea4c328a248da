#include "core/index/kdtree.h"

#include <algorithm>
#include <limits>
#include <type_traits>

#include "core/description/arc_types.h"
#include "core/index/leaf_scan.h"
#include "core/support/cell_queue.h"

namespace kg {

int kdtree_depth(std::uint32_t n) {
  int depth = 0;
  // Leaves at depth L hold at most ceil(n / 2^L) points.
  while (depth < kMaxTreeDepth && ((static_cast<std::uint64_t>(n) + (1ULL << depth) - 1) >> depth) >
                                      static_cast<std::uint64_t>(kLeafSize)) {
    ++depth;
  }
  return depth;
}

namespace {

// A point with its index in the source: the build permutes these in place,
// so its scans and partitions read memory in order (an index array into
// the points made every comparison a cache miss on large indexes).
template <class T, std::size_t D>
struct BuildPoint {
  KdPoint<T, D> p;
  std::uint32_t id;
};

template <class T, std::size_t D>
void build_node(BuildPoint<T, D>* points, std::vector<typename KdTraits<T>::Node>& nodes,
                std::uint32_t node, std::uint32_t begin, std::uint32_t end, int level, int depth,
                double attribute_weight) {
  if (level == depth) return;
  // Split on the dimension of largest (weighted) spread.
  KdPoint<T, D> lo{}, hi{};
  if (end > begin) lo = hi = points[begin].p;
  for (std::uint32_t i = begin + 1; i < end; ++i) {
    const KdPoint<T, D>& v = points[i].p;
    for (std::size_t d = 0; d < D; ++d) {
      lo[d] = std::min(lo[d], v[d]);
      hi[d] = std::max(hi[d], v[d]);
    }
  }
  std::uint32_t best_dim = 0;
  double best_spread = -1;
  for (std::uint32_t d = 0; d < D; ++d) {
    double spread = static_cast<double>(hi[d]) - static_cast<double>(lo[d]);
    if (d >= static_cast<std::uint32_t>(kDescriptorSize)) spread *= attribute_weight;
    if (spread > best_spread) {
      best_spread = spread;
      best_dim = d;
    }
  }
  const std::uint32_t mid = begin + (end - begin) / 2;
  if (end > begin) {
    // Ties broken by source index: the tree does not depend on the order
    // the points came in, and the same comparisons as ever keep indexes
    // byte-identical.
    std::nth_element(points + begin, points + mid, points + end,
                     [best_dim](const BuildPoint<T, D>& a, const BuildPoint<T, D>& b) {
                       const T va = a.p[best_dim], vb = b.p[best_dim];
                       return va < vb || (va == vb && a.id < b.id);
                     });
  }
  nodes[node].dim = static_cast<decltype(nodes[node].dim)>(best_dim);
  nodes[node].split = mid < end ? points[mid].p[best_dim] : T{0};
  build_node<T, D>(points, nodes, 2 * node + 1, begin, mid, level + 1, depth, attribute_weight);
  build_node<T, D>(points, nodes, 2 * node + 2, mid, end, level + 1, depth, attribute_weight);
}

}  // namespace

template <class T, std::size_t D>
void build_kdtree(const KdPoint<T, D>* source, std::uint32_t n, std::vector<KdPoint<T, D>>& points,
                  std::vector<std::uint32_t>& ids, std::vector<typename KdTraits<T>::Node>& nodes,
                  double attribute_weight) {
  const int depth = kdtree_depth(n);
  nodes.assign((static_cast<std::size_t>(1) << depth) - 1, typename KdTraits<T>::Node{});
  std::vector<BuildPoint<T, D>> work(n);
  for (std::uint32_t i = 0; i < n; ++i) work[i] = {source[i], i};
  build_node<T, D>(work.data(), nodes, 0, 0, n, 0, depth, attribute_weight);
  points.resize(n);
  ids.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    points[i] = work[i].p;
    ids[i] = work[i].id;
  }
}

template <class T, std::size_t D>
void kdtree_leaf_bounds(const KdPoint<T, D>* points, std::uint32_t n,
                        std::vector<KdPoint<T, D>>& out) {
  const int depth = kdtree_depth(n);
  const std::size_t leaves = std::size_t{1} << depth;
  out.assign(2 * leaves, KdPoint<T, D>{});
  // Leaf l of the last level covers the range reached by halving [0, n)
  // along l's bits, most significant first.
  for (std::size_t l = 0; l < leaves; ++l) {
    std::uint32_t b = 0, e = n;
    for (int bit = depth - 1; bit >= 0; --bit) {
      const std::uint32_t m = b + (e - b) / 2;
      if ((l >> bit) & 1) {
        b = m;
      } else {
        e = m;
      }
    }
    KdPoint<T, D>& lo = out[2 * l];
    KdPoint<T, D>& hi = out[2 * l + 1];
    lo.fill(std::numeric_limits<T>::max());
    hi.fill(std::numeric_limits<T>::lowest());
    for (std::uint32_t i = b; i < e; ++i) {
      for (std::size_t d = 0; d < D; ++d) {
        lo[d] = std::min(lo[d], points[i][d]);
        hi[d] = std::max(hi[d], points[i][d]);
      }
    }
  }
}

#define KG_INSTANTIATE_BUILD(T, D)                                                           \
  template void build_kdtree<T, D>(const KdPoint<T, D>*, std::uint32_t,                      \
                                   std::vector<KdPoint<T, D>>&, std::vector<std::uint32_t>&, \
                                   std::vector<typename KdTraits<T>::Node>&, double);        \
  template void kdtree_leaf_bounds<T, D>(const KdPoint<T, D>*, std::uint32_t,                \
                                         std::vector<KdPoint<T, D>>&);
KG_INSTANTIATE_BUILD(float, kDescriptorSize)
KG_INSTANTIATE_BUILD(std::int16_t, kDescriptorSize)
KG_INSTANTIATE_BUILD(std::int8_t, kDescriptorSize)
KG_INSTANTIATE_BUILD(float, kSearchDims)
KG_INSTANTIATE_BUILD(std::int16_t, kSearchDims)
KG_INSTANTIATE_BUILD(std::int8_t, kSearchDims)
#undef KG_INSTANTIATE_BUILD

namespace {

// A subtree still to visit. `offset` holds, per dimension, the distance
// from the query to the subtree's cell along that axis; `bound` is the sum
// of their squares, a lower bound of the squared distance to any point in
// the cell (the incremental bound of Arya & Mount).
// Attributes (offsets past kDescriptorSize) are not in the bound: they are
// only compared with the box when a far child is pushed.
template <class T>
struct Frame {
  using Dist = typename KdTraits<T>::Dist;
  std::uint32_t node;
  std::uint32_t begin;
  std::uint32_t end;
  int level;
  Dist bound;
  typename KdTraits<T>::Offset offset[kSearchDims];
  // Approximate search only: the order in which cells are visited, `bound`
  // plus a penalty per attribute offset (attributes do not bound the
  // distance but do make a match less likely).
  double priority;
};

// Pushes the two children of `f`, the far one first so the near one is
// searched first; the far one only when it can hold points within `box` on
// an attribute split. The node's dimension is below D (validated on load).
template <class T, std::size_t D>
inline void push_children(const Frame<T>& f, const typename KdTraits<T>::Node& node,
                          const KdPoint<T, D>& q, typename KdTraits<T>::Dist box, Frame<T>* stack,
                          int& top) {
  using Dist = typename KdTraits<T>::Dist;
  const std::uint32_t mid = f.begin + (f.end - f.begin) / 2;
  const std::uint32_t dim = node.dim;
  const Dist diff = static_cast<Dist>(q[dim]) - static_cast<Dist>(node.split);
  const bool attribute = dim >= static_cast<std::uint32_t>(kDescriptorSize);
  const bool far_reachable = !attribute || (diff <= 0 ? -diff : diff) <= box;
  Frame<T>* far = nullptr;
  if (far_reachable) {
    far = &stack[top++];
    *far = f;
    far->level = f.level + 1;
    if (!attribute) {
      const Dist old = f.offset[dim];
      far->bound = f.bound - old * old + diff * diff;
      far->offset[dim] = static_cast<typename KdTraits<T>::Offset>(diff);
    }
  }
  Frame<T>& near = stack[top++];
  near = f;
  near.level = f.level + 1;
  if (diff <= 0) {  // query on the left: far is the right child
    if (far != nullptr) {
      far->node = 2 * f.node + 2;
      far->begin = mid;
    }
    near.node = 2 * f.node + 1;
    near.end = mid;
  } else {
    if (far != nullptr) {
      far->node = 2 * f.node + 1;
      far->end = mid;
    }
    near.node = 2 * f.node + 2;
    near.begin = mid;
  }
}

// Moves `f` to its near child and pushes the far one when it can still hold
// a match (bound below radius2, within `box` on an attribute split): the
// radius search walks down without copying the frame it stays in.
template <class T, std::size_t D>
inline void descend_near(Frame<T>& f, const typename KdTraits<T>::Node& node,
                         const KdPoint<T, D>& q, typename KdTraits<T>::Dist radius2,
                         typename KdTraits<T>::Dist box, Frame<T>* stack, int& top) {
  using Dist = typename KdTraits<T>::Dist;
  const std::uint32_t mid = f.begin + (f.end - f.begin) / 2;
  const std::uint32_t dim = node.dim;
  const Dist diff = static_cast<Dist>(q[dim]) - static_cast<Dist>(node.split);
  const bool left = diff <= 0;  // the query's side: near is the left child
  if (dim >= static_cast<std::uint32_t>(kDescriptorSize)) {
    if ((left ? -diff : diff) <= box) {
      Frame<T>& far = stack[top++];
      far = f;
      far.level = f.level + 1;
      far.node = left ? 2 * f.node + 2 : 2 * f.node + 1;
      (left ? far.begin : far.end) = mid;
    }
  } else {
    const Dist old = f.offset[dim];
    const Dist far_bound = f.bound - old * old + diff * diff;
    if (far_bound < radius2) {
      Frame<T>& far = stack[top++];
      far = f;
      far.level = f.level + 1;
      far.bound = far_bound;
      far.offset[dim] = static_cast<typename KdTraits<T>::Offset>(diff);
      far.node = left ? 2 * f.node + 2 : 2 * f.node + 1;
      (left ? far.begin : far.end) = mid;
    }
  }
  f.level += 1;
  f.node = left ? 2 * f.node + 1 : 2 * f.node + 2;
  (left ? f.end : f.begin) = mid;
}

// Where the approximate search's walk is: a cell's node, slots and level.
// Walking to the near child changes only these (its offsets, bound and
// priority are its parent's), so they stay in registers; copying the whole
// frame each level stalled on forwarding the narrow stores to the wide
// loads of the copy.
struct Walk {
  std::uint32_t node;
  std::uint32_t begin;
  std::uint32_t end;
  int level;
};

// descend_near for the approximate search, without a branch on the data:
// moves `w` (inside the popped cell `cell`) to its near child and writes
// the far one, ranked (an attribute offset of one box costs as much as the
// whole radius), to `far`; returns whether the far child can still hold a
// match. Every choice is a select: the branches on the query's side and on
// the kind of split mispredicted about half the time.
template <class T, std::size_t D>
inline bool descend_ranked(Walk& w, const Frame<T>& cell, const typename KdTraits<T>::Node& node,
                           const KdPoint<T, D>& q, typename KdTraits<T>::Dist radius2,
                           typename KdTraits<T>::Dist box, const double* cost, Frame<T>& far) {
  using Dist = typename KdTraits<T>::Dist;
  const std::uint32_t mid = w.begin + (w.end - w.begin) / 2;
  const std::uint32_t dim = node.dim;
  const Dist diff = static_cast<Dist>(q[dim]) - static_cast<Dist>(node.split);
  // The query's side (1: near is the left child) and the kind of split, as
  // integers so that the compiler selects instead of branching.
  const std::uint32_t left = diff <= 0 ? 1u : 0u;
  const std::uint32_t attribute = dim >= static_cast<std::uint32_t>(kDescriptorSize) ? 1u : 0u;
  const std::uint32_t left_mask = 0u - left;
  const Dist old = cell.offset[dim];
  const Dist delta = diff * diff - old * old;
  far.node = 2 * w.node + 1 + left;
  far.begin = (mid & left_mask) | (w.begin & ~left_mask);
  far.end = (w.end & left_mask) | (mid & ~left_mask);
  far.level = w.level + 1;
  far.bound = cell.bound + delta * static_cast<Dist>(1 - attribute);
  std::copy(cell.offset, cell.offset + kSearchDims, far.offset);
  far.offset[dim] = static_cast<typename KdTraits<T>::Offset>(diff);
  far.priority = cell.priority + cost[attribute] * static_cast<double>(delta);
  const Dist magnitude = diff < 0 ? -diff : diff;
  w.node = 2 * w.node + 2 - left;
  w.begin = (w.begin & left_mask) | (mid & ~left_mask);
  w.end = (mid & left_mask) | (w.end & ~left_mask);
  w.level += 1;
  const std::uint32_t in_box = magnitude <= box ? 1u : 0u;
  const std::uint32_t in_ball = far.bound < radius2 ? 1u : 0u;
  return ((attribute & in_box) | ((1 - attribute) & in_ball)) != 0;
}

// Whether a leaf whose points lie in [lo, hi] (bounds[0], bounds[1]) can
// hold a point within radius2 (descriptor components) and `box`
// (attributes) of q.
template <class T, std::size_t D>
inline bool box_can_match(const std::array<T, D>* bounds, const std::array<T, D>& q,
                          typename KdTraits<T>::Dist radius2, typename KdTraits<T>::Dist box) {
  using Dist = typename KdTraits<T>::Dist;
  const std::array<T, D>& lo = bounds[0];
  const std::array<T, D>& hi = bounds[1];
  Dist d2 = 0;
  for (int d = 0; d < kDescriptorSize; ++d) {
    const Dist below = static_cast<Dist>(lo[d]) - static_cast<Dist>(q[d]);
    const Dist above = static_cast<Dist>(q[d]) - static_cast<Dist>(hi[d]);
    const Dist gap = below > 0 ? below : above > 0 ? above : 0;
    d2 += gap * gap;
  }
  if (!(d2 < radius2)) return false;
  for (std::size_t d = kDescriptorSize; d < D; ++d) {
    if (static_cast<Dist>(lo[d]) - static_cast<Dist>(q[d]) > box ||
        static_cast<Dist>(q[d]) - static_cast<Dist>(hi[d]) > box)
      return false;
  }
  return true;
}

template <class T, std::size_t D>
inline bool within_box(const std::array<T, D>& p, const std::array<T, D>& q,
                       typename KdTraits<T>::Dist box) {
  using Dist = typename KdTraits<T>::Dist;
  for (std::size_t d = kDescriptorSize; d < D; ++d) {
    const Dist diff = static_cast<Dist>(p[d]) - static_cast<Dist>(q[d]);
    if ((diff < 0 ? -diff : diff) > box) return false;
  }
  return true;
}

template <class T>
inline Frame<T> root_frame(std::uint32_t n) {
  Frame<T> f{};
  f.end = n;
  return f;
}

}  // namespace

namespace {

// What a search writes for a point found: its id.
struct IdOut {
  std::uint32_t* out;
  void put(std::uint32_t i, std::uint32_t id) const { out[i] = id; }
  // A whole leaf's hits (positions in slots [begin, begin + n)) from out[at]
  // on, in a loop the compiler widens.
  void put_leaf(std::uint32_t at, std::uint32_t begin, std::uint32_t, const std::uint16_t* hits,
                std::uint32_t count) const {
    std::uint32_t* const to = out + at;
    for (std::uint32_t h = 0; h < count; ++h) to[h] = begin + hits[h];
  }
  void prefetch(std::uint32_t, std::uint32_t) const {}
};

// The arc key of the point with that id (the model index's slot).
struct ArcKeyOut {
  std::uint64_t* out;
  KdArcKeys keys;
  void put(std::uint32_t i, std::uint32_t id) const {
    const std::uint32_t from = keys.from[id];
    const auto to =
        static_cast<std::uint32_t>(static_cast<std::int64_t>(from) + keys.to_offset[id]);
    out[i] = (static_cast<std::uint64_t>(from) << 32) | to;
  }
  // A whole leaf's hits: one look-up each (the keys of the whole leaf in a
  // widened loop, then picked, cost more).
  void put_leaf(std::uint32_t at, std::uint32_t begin, std::uint32_t, const std::uint16_t* hits,
                std::uint32_t count) const {
    std::uint64_t* const to = out + at;
    for (std::uint32_t h = 0; h < count; ++h) {
      const std::uint32_t slot = begin + hits[h];
      const std::uint32_t from = keys.from[slot];
      to[h] = (static_cast<std::uint64_t>(from) << 32) |
              (from + static_cast<std::uint32_t>(keys.to_offset[slot]));  // mod 2^32, as arc()
    }
  }
  // Asks the cache for the arcs of slots [begin, end), as the leaf's points.
  void prefetch(std::uint32_t begin, std::uint32_t end) const {
    prefetch_range(keys.from + begin, keys.from + end);
    prefetch_range(keys.to_offset + begin, keys.to_offset + end);
  }
  template <class P>
  static void prefetch_range(const P* first, const P* last) {
    const char* p = reinterpret_cast<const char*>(first);
    const char* end = reinterpret_cast<const char*>(last);
    for (; p < end; p += 64) __builtin_prefetch(p);
  }
};

}  // namespace

template <class T, std::size_t D>
template <class Out>
void BasicKdTreeView<T, D>::scan_leaf(std::uint32_t node, std::uint32_t begin, std::uint32_t end,
                                      const Point& q, Dist radius2, Dist box, const Out& out,
                                      std::uint32_t capacity, std::uint32_t& found,
                                      RankedHits* ranked) const {
  const Point* bounds =
      bounds_ != nullptr ? bounds_ + 2 * (node - ((std::uint32_t{1} << depth_) - 1)) : nullptr;
  if constexpr (std::is_same_v<T, std::int8_t> && D == kSearchDims) {
    // The model index's default: the vectorised bounds test and leaf scan.
    if (bounds != nullptr && !leaf_may_match_i8(bounds, q, radius2, box)) return;
    std::uint16_t hits[kLeafSize];
    if (ranked != nullptr) {
      // Written as without a cap, each hit's rank code beside it (at its
      // position in the output) for the cut (approximate()).
      std::uint8_t leaf_ranks[kLeafSize];
      const int n =
          scan_leaf_i8_ranked(points_ + begin, static_cast<int>(end - begin), q, radius2, box,
                              {ranked->descriptor, ranked->attribute}, hits, leaf_ranks);
      const auto count = static_cast<std::uint32_t>(n);
      std::uint16_t* const codes = ranked->count;
      if (ids_ == nullptr && count <= capacity && found <= capacity - count) {
        out.put_leaf(found, begin, end - begin, hits, count);
        std::uint8_t* const ranks = ranked->ranks + found;
        for (std::uint32_t h = 0; h < count; ++h) {
          const std::uint8_t r = leaf_ranks[hits[h]];
          ranks[h] = r;
          ++codes[r];
        }
        found += count;
        return;
      }
      for (int h = 0; h < n; ++h) {
        if (found < capacity) {
          out.put(found, id(begin + hits[h]));
          ranked->ranks[found] = leaf_ranks[hits[h]];
          ++codes[leaf_ranks[hits[h]]];
        }
        ++found;
      }
      return;
    }
    const int n =
        scan_leaf_i8(points_ + begin, static_cast<int>(end - begin), q, radius2, box, hits);
    const auto count = static_cast<std::uint32_t>(n);
    if (ids_ == nullptr && count <= capacity && found <= capacity - count) {
      // The model index's case (slots are ids) with room for the whole
      // leaf: no test per hit, and the compiler widens the hits in vectors
      // (the per-hit loop below was a tenth of the search).
      out.put_leaf(found, begin, end - begin, hits, count);
      found += count;
      return;
    }
    for (int h = 0; h < n; ++h) {
      if (found < capacity) out.put(found, id(begin + hits[h]));
      ++found;
    }
  } else {
    if (bounds != nullptr && !box_can_match(bounds, q, radius2, box)) return;
    for (std::uint32_t i = begin; i < end; ++i) {
      const Dist d2 = kd_distance2(points_[i], q);
      if (d2 < radius2 && within_box(points_[i], q, box)) {
        if (found < capacity) {
          out.put(found, id(i));
          if (ranked != nullptr) {
            Dist a2 = 0;
            for (std::size_t d = kDescriptorSize; d < D; ++d) {
              const Dist e = static_cast<Dist>(points_[i][d]) - static_cast<Dist>(q[d]);
              a2 += e * e;
            }
            const float r = static_cast<float>(d2) * ranked->descriptor +
                            static_cast<float>(a2) * ranked->attribute;
            const std::uint8_t code = r >= 255.f ? std::uint8_t{255} : static_cast<std::uint8_t>(r);
            ranked->ranks[found] = code;
            ++ranked->count[code];
          }
        }
        ++found;
      }
    }
  }
}

template <class T, std::size_t D>
void BasicKdTreeView<T, D>::prefetch_leaf(std::uint32_t node, std::uint32_t begin,
                                          std::uint32_t end) const {
  if (bounds_ != nullptr)
    __builtin_prefetch(bounds_ + 2 * (node - ((std::uint32_t{1} << depth_) - 1)));
  const char* first = reinterpret_cast<const char*>(points_ + begin);
  const char* last = reinterpret_cast<const char*>(points_ + end);
  for (const char* p = first; p < last; p += 64) __builtin_prefetch(p);
}

template <class T, std::size_t D>
std::uint32_t BasicKdTreeView<T, D>::radius_search(const Point& q, Dist radius2, std::uint32_t* out,
                                                   std::uint32_t capacity) const {
  return radius_search(q, radius2, std::numeric_limits<Dist>::max(), out, capacity);
}

template <class T, std::size_t D>
std::uint32_t BasicKdTreeView<T, D>::radius_search(const Point& q, Dist radius2, Dist box,
                                                   std::uint32_t* out,
                                                   std::uint32_t capacity) const {
  std::uint32_t found = 0;
  if (n_ == 0) return 0;
  // Depth-first with the far child pushed first: at most one pending
  // sibling per level, so depth + 2 frames always suffice.
  Frame<T> stack[kMaxTreeDepth + 2];
  int top = 0;
  stack[top++] = root_frame<T>(n_);
  while (top > 0) {
    Frame<T> f = stack[--top];
    if (f.bound >= radius2) continue;
    while (f.level < depth_) descend_near<T, D>(f, nodes_[f.node], q, radius2, box, stack, top);
    scan_leaf(f.node, f.begin, f.end, q, radius2, box, IdOut{out}, capacity, found);
  }
  return found;
}

template <class T, std::size_t D>
std::uint32_t BasicKdTreeView<T, D>::radius_search_approximate(const Point& q, Dist radius2,
                                                               Dist box, int max_leaves,
                                                               std::uint32_t* out,
                                                               std::uint32_t capacity) const {
  return approximate(q, radius2, box, max_leaves, IdOut{out}, capacity);
}

template <class T, std::size_t D>
std::uint32_t BasicKdTreeView<T, D>::radius_search_approximate(const Point& q, Dist radius2,
                                                               Dist box, int max_leaves,
                                                               const KdArcKeys& keys,
                                                               std::uint64_t* out,
                                                               std::uint32_t capacity) const {
  return approximate(q, radius2, box, max_leaves, ArcKeyOut{out, keys}, capacity);
}

template <class T, std::size_t D>
std::uint32_t BasicKdTreeView<T, D>::radius_search_approximate(
    const Point& q, Dist radius2, Dist box, int max_leaves, const KdArcKeys& keys,
    const KdRanking& ranking, std::uint64_t* out, std::uint32_t capacity) const {
  return approximate(q, radius2, box, max_leaves, ArcKeyOut{out, keys}, capacity,
                     ranking.max_hits > 0 ? &ranking : nullptr);
}

template <class T, std::size_t D>
template <class Out>
std::uint32_t BasicKdTreeView<T, D>::approximate(const Point& q, Dist radius2, Dist box,
                                                 int max_leaves, const Out& out,
                                                 std::uint32_t capacity,
                                                 const KdRanking* ranking) const {
  std::uint32_t found = 0;
  if (n_ == 0 || max_leaves <= 0) return 0;
  // Pending far children live in `cells`; the min-heap orders small
  // (priority, cell) entries so sifting moves 16 bytes, not whole cells.
  // When all cells are taken, further far children are dropped (the answer
  // is approximate anyway).
  constexpr int kCells = 512;
  Frame<T> cells[kCells + 1];  // cells[kCells]: where dropped far children go
  PendingCell heap[kCells];    // one entry per cell in use, the sink never
  int free_cells[kCells];
  int n_free = 0, n_used = 0, size = 0;
  std::uint32_t pushed = 0;
  // An attribute offset of `box` ranks like a descriptor offset of the radius.
  const double box_width = std::is_floating_point_v<T> ? std::max(static_cast<double>(box), 1e-6)
                                                       : static_cast<double>(box) + 1.0;
  // Priority per unit of squared offset: descriptor, then attribute.
  const double cost[2] = {1.0, static_cast<double>(radius2) / (box_width * box_width)};
  // After `leaves` leaves at most max_leaves - leaves more cells are
  // popped, so a cell ranked below that many pending ones never is. With a
  // budget of up to kBoundedLeaves the queue keeps only those, sorted, the
  // best at heap[head] (pops are then reads, and most far children are
  // dropped with one compare), and frees the others' cells; the cells
  // visited are the heap's (cells never run out at these budgets).
  constexpr int kBoundedLeaves = 64;
  const bool bounded = max_leaves <= kBoundedLeaves;
  // A cap on the hits: each hit's rank code is kept beside it, then the
  // best stay (bounded budgets only: at most kBoundedLeaves leaves of
  // kLeafSize points).
  if (!bounded) ranking = nullptr;
  std::uint8_t ranked_codes[kBoundedLeaves * kLeafSize];
  RankedHits collected{ranked_codes, {}, 0.f, 0.f};
  RankedHits* ranked = nullptr;
  if (ranking != nullptr) {
    collected.descriptor = ranking->descriptor;
    collected.attribute = ranking->attribute;
    ranked = &collected;
  }
  int head = 0;  // bounded: heap[head..size), keys ascending
  auto push = [&](PendingCell x, int remaining) {
    if (!bounded) {
      push_pending(heap, size, x);
      return;
    }
    if (size - head >= remaining) {
      if (remaining <= 0 || x.key > heap[size - 1].key) {
        free_cells[n_free++] = x.cell;
        return;
      }
      free_cells[n_free++] = heap[--size].cell;
    }
    int i = size++;
    for (; i > head && heap[i - 1].key > x.key; --i) heap[i] = heap[i - 1];
    heap[i] = x;
  };
  cells[n_used] = root_frame<T>(n_);
  push({pending_key(0.0, pushed++), n_used++}, max_leaves);
  int leaves = 0;
  constexpr int kBatch = 8;
  struct Leaf {
    std::uint32_t node, begin, end;
  };
  Leaf batch[kBatch];
  int n_batch = 0;
  while (size > head && leaves < max_leaves) {
    const int cell = bounded ? heap[head++].cell : pop_pending(heap, size).cell;
    const Frame<T> f = cells[cell];  // a copy: the cell is free for the first far child
    free_cells[n_free++] = cell;
    Walk w{f.node, f.begin, f.end, f.level};
    // The far children of the walk go straight into the next free cells
    // (into cells[kCells] when none is left) and are queued once it ends:
    // the cell bookkeeping is arithmetic on whether each is kept.
    PendingCell kept[kMaxTreeDepth];
    int n_kept = 0;
    while (w.level < depth_) {
      const int reuse = n_free > 0 ? 1 : 0;
      const int free_slot = free_cells[n_free - reuse];  // index 0 when there is none
      const int slot = reuse ? free_slot : n_used;       // n_used == kCells: the sink
      const int room = slot < kCells ? 1 : 0;
      const int keep =
          (descend_ranked<T, D>(w, f, nodes_[w.node], q, radius2, box, cost, cells[slot]) ? 1 : 0) &
          room;
      kept[n_kept] = {pending_key(cells[slot].priority, pushed), slot};
      pushed += static_cast<std::uint32_t>(keep);
      n_kept += keep;
      n_free -= keep & reuse;
      n_used += keep & (1 - reuse);
    }
    ++leaves;
    for (int k = 0; k < n_kept; ++k) push(kept[k], max_leaves - leaves);
    // The walk never depends on what the leaves hold, so leaves are scanned
    // in batches after their memory has been requested: the misses of a
    // batch overlap instead of stalling one after another.
    batch[n_batch++] = {w.node, w.begin, w.end};
    prefetch_leaf(w.node, w.begin, w.end);
    out.prefetch(w.begin, w.end);
    if (n_batch == kBatch) {
      for (int b = 0; b < n_batch; ++b)
        scan_leaf(batch[b].node, batch[b].begin, batch[b].end, q, radius2, box, out, capacity,
                  found, ranked);
      n_batch = 0;
    }
  }
  for (int b = 0; b < n_batch; ++b)
    scan_leaf(batch[b].node, batch[b].begin, batch[b].end, q, radius2, box, out, capacity, found,
              ranked);
  if (ranked == nullptr) return found;
  // More hits than the output holds: no cut (the first ones, truncated,
  // as without a cap).
  if (found > capacity || found <= ranking->max_hits) return found;
  // The cut: the hits ranked below the first code at which their count
  // would pass max_hits, in the order found.
  std::uint32_t keep = 0;
  int cut = 0;
  while (keep + collected.count[cut] <= ranking->max_hits) keep += collected.count[cut++];
  auto* const keys = out.out;
  std::uint32_t kept = 0;
  for (std::uint32_t i = 0; i < found; ++i) {
    // Branch-free: an entry copied past the kept ones is overwritten next.
    keys[kept] = keys[i];
    kept += ranked_codes[i] < cut ? 1u : 0u;
  }
  return kept;
}

template <class T, std::size_t D>
int BasicKdTreeView<T, D>::knn_search(const Point& q, int k, std::uint32_t* ids,
                                      Dist* dist2) const {
  if (k > 64) k = 64;
  if (k <= 0 || n_ == 0) return 0;
  int count = 0;  // ids/dist2 kept sorted ascending
  Frame<T> stack[kMaxTreeDepth + 2];
  int top = 0;
  stack[top++] = root_frame<T>(n_);
  while (top > 0) {
    const Frame<T> f = stack[--top];
    if (count == k && f.bound > dist2[count - 1]) continue;
    if (f.level == depth_) {
      for (std::uint32_t i = f.begin; i < f.end; ++i) {
        const Dist d = kd_distance2(points_[i], q);
        const std::uint32_t pid = id(i);
        // Kept when closer than the k-th, or as close with a smaller id.
        if (count == k && (d > dist2[count - 1] || (d == dist2[count - 1] && pid > ids[count - 1])))
          continue;
        int pos = count < k ? count++ : k - 1;
        while (pos > 0 && (dist2[pos - 1] > d || (dist2[pos - 1] == d && ids[pos - 1] > pid))) {
          dist2[pos] = dist2[pos - 1];
          ids[pos] = ids[pos - 1];
          --pos;
        }
        dist2[pos] = d;
        ids[pos] = pid;
      }
      continue;
    }
    push_children<T, D>(f, nodes_[f.node], q, std::numeric_limits<Dist>::max(), stack, top);
  }
  return count;
}

template class BasicKdTreeView<float>;
template class BasicKdTreeView<std::int16_t>;
template class BasicKdTreeView<std::int8_t>;
template class BasicKdTreeView<float, kSearchDims>;
template class BasicKdTreeView<std::int16_t, kSearchDims>;
template class BasicKdTreeView<std::int8_t, kSearchDims>;

}  // namespace kg
