#include "core/kdtree.h"

#include <algorithm>

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

template <class T>
void build_node(const std::vector<KdPoint<T>>& points,
                std::vector<typename KdTraits<T>::Node>& nodes, std::vector<std::uint32_t>& order,
                std::uint32_t node, std::uint32_t begin, std::uint32_t end, int level, int depth) {
  using Dist = typename KdTraits<T>::Dist;
  if (level == depth) return;
  // Split on the dimension of largest spread.
  std::uint32_t best_dim = 0;
  Dist best_spread = -1;
  for (std::uint32_t d = 0; d < kDescriptorSize; ++d) {
    T lo = 0, hi = 0;
    for (std::uint32_t i = begin; i < end; ++i) {
      const T v = points[order[i]][d];
      if (i == begin || v < lo) lo = v;
      if (i == begin || v > hi) hi = v;
    }
    const Dist spread = static_cast<Dist>(hi) - static_cast<Dist>(lo);
    if (spread > best_spread) {
      best_spread = spread;
      best_dim = d;
    }
  }
  const std::uint32_t mid = begin + (end - begin) / 2;
  if (end > begin) {
    std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                     [&](std::uint32_t a, std::uint32_t b) {
                       const T va = points[a][best_dim], vb = points[b][best_dim];
                       return va < vb || (va == vb && a < b);
                     });
  }
  nodes[node].dim = static_cast<decltype(nodes[node].dim)>(best_dim);
  nodes[node].split = mid < end ? points[order[mid]][best_dim] : T{0};
  build_node<T>(points, nodes, order, 2 * node + 1, begin, mid, level + 1, depth);
  build_node<T>(points, nodes, order, 2 * node + 2, mid, end, level + 1, depth);
}

}  // namespace

template <class T>
void build_kdtree(const KdPoint<T>* source, std::uint32_t n, std::vector<KdPoint<T>>& points,
                  std::vector<std::uint32_t>& ids, std::vector<typename KdTraits<T>::Node>& nodes) {
  const int depth = kdtree_depth(n);
  nodes.assign((static_cast<std::size_t>(1) << depth) - 1, typename KdTraits<T>::Node{});
  const std::vector<KdPoint<T>> copy(source, source + n);
  std::vector<std::uint32_t> order(n);
  for (std::uint32_t i = 0; i < n; ++i) order[i] = i;
  build_node<T>(copy, nodes, order, 0, 0, n, 0, depth);
  points.resize(n);
  ids.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    points[i] = copy[order[i]];
    ids[i] = order[i];
  }
}

template void build_kdtree<float>(const KdPoint<float>*, std::uint32_t,
                                  std::vector<KdPoint<float>>&, std::vector<std::uint32_t>&,
                                  std::vector<KdNode>&);
template void build_kdtree<std::int16_t>(const KdPoint<std::int16_t>*, std::uint32_t,
                                         std::vector<KdPoint<std::int16_t>>&,
                                         std::vector<std::uint32_t>&, std::vector<KdNodeInt>&);
template void build_kdtree<std::int8_t>(const KdPoint<std::int8_t>*, std::uint32_t,
                                        std::vector<KdPoint<std::int8_t>>&,
                                        std::vector<std::uint32_t>&, std::vector<KdNodeInt>&);

namespace {

// A subtree still to visit. `offset` holds, per dimension, the distance
// from the query to the subtree's cell along that axis; `bound` is the sum
// of their squares, a lower bound of the squared distance to any point in
// the cell (the incremental bound of Arya & Mount).
template <class T>
struct Frame {
  using Dist = typename KdTraits<T>::Dist;
  std::uint32_t node;
  std::uint32_t begin;
  std::uint32_t end;
  int level;
  Dist bound;
  Dist offset[kDescriptorSize];
};

// Pushes the two children of `f`, the far one first so the near one is
// searched first.
template <class T>
inline void push_children(const Frame<T>& f, const typename KdTraits<T>::Node& node,
                          const KdPoint<T>& q, Frame<T>* stack, int& top) {
  using Dist = typename KdTraits<T>::Dist;
  const std::uint32_t mid = f.begin + (f.end - f.begin) / 2;
  const Dist diff = static_cast<Dist>(q[node.dim]) - static_cast<Dist>(node.split);
  const Dist old = f.offset[node.dim];
  Frame<T>& far = stack[top++];
  far = f;
  far.level = f.level + 1;
  far.bound = f.bound - old * old + diff * diff;
  far.offset[node.dim] = diff;
  Frame<T>& near = stack[top++];
  near = f;
  near.level = f.level + 1;
  if (diff <= 0) {  // query on the left: far is the right child
    far.node = 2 * f.node + 2;
    far.begin = mid;
    near.node = 2 * f.node + 1;
    near.end = mid;
  } else {
    far.node = 2 * f.node + 1;
    far.end = mid;
    near.node = 2 * f.node + 2;
    near.begin = mid;
  }
}

template <class T>
inline Frame<T> root_frame(std::uint32_t n) {
  Frame<T> f{};
  f.end = n;
  return f;
}

}  // namespace

template <class T>
std::uint32_t BasicKdTreeView<T>::radius_search(const Point& q, Dist radius2, std::uint32_t* out,
                                                std::uint32_t capacity) const {
  std::uint32_t found = 0;
  if (n_ == 0) return 0;
  // Depth-first with the far child pushed first: at most one pending
  // sibling per level, so depth + 2 frames always suffice.
  Frame<T> stack[kMaxTreeDepth + 2];
  int top = 0;
  stack[top++] = root_frame<T>(n_);
  while (top > 0) {
    const Frame<T> f = stack[--top];
    if (f.bound >= radius2) continue;
    if (f.level == depth_) {
      for (std::uint32_t i = f.begin; i < f.end; ++i) {
        if (kd_distance2<T>(points_[i], q) < radius2) {
          if (found < capacity) out[found] = id(i);
          ++found;
        }
      }
      continue;
    }
    push_children<T>(f, nodes_[f.node], q, stack, top);
  }
  return found;
}

template <class T>
int BasicKdTreeView<T>::knn_search(const Point& q, int k, std::uint32_t* ids, Dist* dist2) const {
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
        const Dist d = kd_distance2<T>(points_[i], q);
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
    push_children<T>(f, nodes_[f.node], q, stack, top);
  }
  return count;
}

template class BasicKdTreeView<float>;
template class BasicKdTreeView<std::int16_t>;
template class BasicKdTreeView<std::int8_t>;

}  // namespace kg
