#include "core/kdtree.h"

#include <algorithm>

#include "core/arc_descriptor.h"

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

void build_node(std::vector<ArcDescriptor>& points, std::vector<std::uint32_t>& ids,
                std::vector<KdNode>& nodes, std::vector<std::uint32_t>& order, std::uint32_t node,
                std::uint32_t begin, std::uint32_t end, int level, int depth) {
  if (level == depth) return;
  // Split on the dimension of largest spread.
  std::uint32_t best_dim = 0;
  float best_spread = -1.f;
  for (std::uint32_t d = 0; d < kDescriptorSize; ++d) {
    float lo = 0.f, hi = 0.f;
    for (std::uint32_t i = begin; i < end; ++i) {
      const float v = points[order[i]][d];
      if (i == begin || v < lo) lo = v;
      if (i == begin || v > hi) hi = v;
    }
    if (hi - lo > best_spread) {
      best_spread = hi - lo;
      best_dim = d;
    }
  }
  const std::uint32_t mid = begin + (end - begin) / 2;
  if (end > begin) {
    std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                     [&](std::uint32_t a, std::uint32_t b) {
                       const float va = points[a][best_dim], vb = points[b][best_dim];
                       return va < vb || (va == vb && a < b);
                     });
  }
  nodes[node].dim = best_dim;
  nodes[node].split = mid < end ? points[order[mid]][best_dim] : 0.f;
  build_node(points, ids, nodes, order, 2 * node + 1, begin, mid, level + 1, depth);
  build_node(points, ids, nodes, order, 2 * node + 2, mid, end, level + 1, depth);
}

}  // namespace

void build_kdtree(const ArcDescriptor* descriptors, std::uint32_t n,
                  std::vector<ArcDescriptor>& points, std::vector<std::uint32_t>& ids,
                  std::vector<KdNode>& nodes) {
  const int depth = kdtree_depth(n);
  nodes.assign((static_cast<std::size_t>(1) << depth) - 1, KdNode{});
  std::vector<ArcDescriptor> source(descriptors, descriptors + n);
  std::vector<std::uint32_t> order(n);
  for (std::uint32_t i = 0; i < n; ++i) order[i] = i;
  build_node(source, ids, nodes, order, 0, 0, n, 0, depth);
  points.resize(n);
  ids.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    points[i] = source[order[i]];
    ids[i] = order[i];
  }
}

namespace {

// A subtree still to visit. `offset` holds, per dimension, the distance
// from the query to the subtree's cell along that axis; `bound` is the sum
// of their squares, a lower bound of the squared distance to any point in
// the cell (the incremental bound of Arya & Mount).
struct Frame {
  std::uint32_t node;
  std::uint32_t begin;
  std::uint32_t end;
  int level;
  float bound;
  float offset[kDescriptorSize];
};

// Pushes the two children of `f`, the far one first so the near one is
// searched first.
inline void push_children(const Frame& f, const KdNode& node, const ArcDescriptor& q, Frame* stack,
                          int& top) {
  const std::uint32_t mid = f.begin + (f.end - f.begin) / 2;
  const float diff = q[node.dim] - node.split;
  const float old = f.offset[node.dim];
  Frame& far = stack[top++];
  far = f;
  far.level = f.level + 1;
  far.bound = f.bound - old * old + diff * diff;
  far.offset[node.dim] = diff;
  Frame& near = stack[top++];
  near = f;
  near.level = f.level + 1;
  if (diff <= 0.f) {  // query on the left: far is the right child
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

inline Frame root_frame(std::uint32_t n) {
  Frame f{};
  f.end = n;
  return f;
}

}  // namespace

std::uint32_t KdTreeView::radius_search(const ArcDescriptor& q, float radius2, std::uint32_t* out,
                                        std::uint32_t capacity) const {
  std::uint32_t found = 0;
  if (n_ == 0) return 0;
  Frame stack[kMaxTreeDepth + 2];
  int top = 0;
  stack[top++] = root_frame(n_);
  while (top > 0) {
    const Frame f = stack[--top];
    if (f.bound >= radius2) continue;
    if (f.level == depth_) {
      for (std::uint32_t i = f.begin; i < f.end; ++i) {
        if (squared_distance(points_[i], q) < radius2) {
          if (found < capacity) out[found] = ids_[i];
          ++found;
        }
      }
      continue;
    }
    push_children(f, nodes_[f.node], q, stack, top);
  }
  return found;
}

int KdTreeView::knn_search(const ArcDescriptor& q, int k, std::uint32_t* ids, float* dist2) const {
  if (k > 64) k = 64;
  if (k <= 0 || n_ == 0) return 0;
  int count = 0;  // ids/dist2 kept sorted ascending
  Frame stack[kMaxTreeDepth + 2];
  int top = 0;
  stack[top++] = root_frame(n_);
  while (top > 0) {
    const Frame f = stack[--top];
    if (count == k && f.bound >= dist2[count - 1]) continue;
    if (f.level == depth_) {
      for (std::uint32_t i = f.begin; i < f.end; ++i) {
        const float d = squared_distance(points_[i], q);
        if (count == k && d >= dist2[count - 1]) continue;
        int pos = count < k ? count++ : k - 1;
        while (pos > 0 && (dist2[pos - 1] > d || (dist2[pos - 1] == d && ids[pos - 1] > ids_[i]))) {
          dist2[pos] = dist2[pos - 1];
          ids[pos] = ids[pos - 1];
          --pos;
        }
        dist2[pos] = d;
        ids[pos] = ids_[i];
      }
      continue;
    }
    push_children(f, nodes_[f.node], q, stack, top);
  }
  return count;
}

}  // namespace kg
