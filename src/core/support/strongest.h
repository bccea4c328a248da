// Keeping the k strongest of a stream in bounded memory: a heap whose front
// is the weakest kept (std heap order under `stronger`).
#pragma once

#include <algorithm>
#include <cstddef>

namespace kg {

// Offers v to `heap` (at most `keep` elements): added while there is room,
// else it replaces the weakest kept when stronger than it.
template <class Heap, class Value, class Stronger>
void offer_strongest(Heap& heap, const Value& v, std::size_t keep, Stronger stronger) {
  if (heap.size() < keep) {
    heap.push_back(v);
    std::push_heap(heap.begin(), heap.end(), stronger);
  } else if (!heap.empty() && stronger(v, heap.front())) {
    std::pop_heap(heap.begin(), heap.end(), stronger);
    heap.back() = v;
    std::push_heap(heap.begin(), heap.end(), stronger);
  }
}

}  // namespace kg
