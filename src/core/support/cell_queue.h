// The approximate kd-tree search's queue of cells still to visit: a binary
// min-heap of (priority, push order) keys, so cells of equal priority come
// out first pushed first, whatever the heap's layout. It replaces
// std::push_heap / pop_heap, whose branches on these random priorities
// mispredicted about once per level (callgrind --branch-sim, graf3 with 10
// models): popping chooses each child with a compare-and-add instead.
#pragma once

#include <cstdint>

namespace kg {

struct PendingCell {
  std::uint64_t key;  // float bits of the priority, then the push order
  int cell;
};

// The key of a cell of `priority` (negative and NaN count as 0) pushed
// `order`-th. Non-negative floats order like their bit patterns; ranking
// in float keeps the push order in the low 32 bits.
inline std::uint64_t pending_key(double priority, std::uint32_t order) {
  const float p = priority > 0.0 ? static_cast<float>(priority) : 0.f;
  std::uint32_t bits;
  __builtin_memcpy(&bits, &p, sizeof bits);
  return (static_cast<std::uint64_t>(bits) << 32) | order;
}

// Places x at the hole heap[i] or above it, moving larger parents down.
inline void sift_up(PendingCell* heap, int i, PendingCell x) {
  while (i > 0) {
    const int parent = (i - 1) / 2;
    if (heap[parent].key <= x.key) break;
    heap[i] = heap[parent];
    i = parent;
  }
  heap[i] = x;
}

// Adds x to heap[0..size); the array must have room for it.
inline void push_pending(PendingCell* heap, int& size, PendingCell x) {
  sift_up(heap, size++, x);
}

// Removes and returns the entry of smallest key (size > 0): the hole left
// at the root moves down along the smaller children to the bottom, and
// the last entry is sifted up from there (it rarely moves). The freed
// slot heap[size] holds a sentinel meanwhile.
inline PendingCell pop_pending(PendingCell* heap, int& size) {
  const PendingCell top = heap[0];
  const PendingCell last = heap[--size];
  heap[size].key = ~std::uint64_t{0};  // a right child at `size` is never chosen
  int i = 0;
  for (int c = 1; c < size; c = 2 * i + 1) {
    c += heap[c + 1].key < heap[c].key ? 1 : 0;
    heap[i] = heap[c];
    i = c;
  }
  sift_up(heap, i, last);
  return top;
}

}  // namespace kg
