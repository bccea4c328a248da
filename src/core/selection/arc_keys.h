// Model-arc keys of the selection (from << 32 | to, both model keypoint
// ids) and the two operations it runs on lists of them: sorting and
// searching. The radix passes and the searches have no data-dependent
// branches (only the insertion sort of lists of at most 16 keys has):
// when the selection sorted every look-up's list (a few thousand lists of
// ~200 random keys a frame, searched tens of thousands of times), the
// branch mispredictions of std::sort and std::lower_bound alone were about
// a third of a frame's time (callgrind --branch-sim on graf3, 10 models).
// It now sorts only the few arcs its semi-join keeps.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace kg {

inline std::uint64_t arc_key(std::uint32_t from, std::uint32_t to) {
  return (static_cast<std::uint64_t>(from) << 32) | to;
}
inline std::uint32_t key_from(std::uint64_t k) {
  return static_cast<std::uint32_t>(k >> 32);
}
inline std::uint32_t key_to(std::uint64_t k) {
  return static_cast<std::uint32_t>(k);
}

// Number of bits that hold every id below `ids` (0 for ids <= 1).
inline int id_bits(std::uint32_t ids) {
  int bits = 0;
  while (bits < 32 && (std::uint64_t{1} << bits) < ids) ++bits;
  return bits;
}

// Sorts keys[0..n) ascending when both ids are below 2^bits: least
// significant digit radix sort over `to` then `from`, each field in as few
// digits of at most 8 bits as hold it (12-bit ids: two 6-bit digits).
// `scratch` holds n keys. Stable, no comparisons; short lists are
// insertion-sorted. With `sorted_by_to`, keys are already in order of `to`
// (a reversed sorted list): only the `from` digits are sorted (tested, not
// used by the selection now).
inline void sort_arc_keys(std::uint64_t* keys, std::uint64_t* scratch, std::uint32_t n, int bits,
                          bool sorted_by_to = false) {
  if (n <= 16) {
    for (std::uint32_t i = 1; i < n; ++i) {
      const std::uint64_t k = keys[i];
      std::uint32_t j = i;
      for (; j > 0 && keys[j - 1] > k; --j) keys[j] = keys[j - 1];
      keys[j] = k;
    }
    return;
  }
  const int digits = (bits + 7) / 8;
  const int width = digits > 0 ? (bits + digits - 1) / digits : 0;
  const std::uint64_t mask = (std::uint64_t{1} << width) - 1;
  std::uint64_t* src = keys;
  std::uint64_t* dst = scratch;
  for (int field = sorted_by_to ? 32 : 0; field < 64; field += 32) {
    for (int d = 0; d < digits; ++d) {
      const int shift = field + d * width;
      std::uint32_t count[257];
      std::memset(count, 0, static_cast<std::size_t>(mask + 2) * sizeof count[0]);
      for (std::uint32_t i = 0; i < n; ++i) ++count[((src[i] >> shift) & mask) + 1];
      for (std::uint64_t b = 0; b < mask + 1; ++b) count[b + 1] += count[b];
      for (std::uint32_t i = 0; i < n; ++i) dst[count[(src[i] >> shift) & mask]++] = src[i];
      std::uint64_t* t = src;
      src = dst;
      dst = t;
    }
  }
  if (src != keys) std::memcpy(keys, src, n * sizeof(std::uint64_t));
}

// First position in the sorted list[0..n) whose key is not below k.
inline const std::uint64_t* lower_bound_key(const std::uint64_t* list, std::uint32_t n,
                                            std::uint64_t k) {
  const std::uint64_t* base = list;
  if (n == 0) return list;
  while (n > 1) {
    const std::uint32_t half = n / 2;
    // A conditional move, not a branch.
    base = base[half] < k ? base + half : base;
    n -= half;
  }
  return base + (*base < k ? 1 : 0);
}

// The keys of the sorted list whose arc starts at `from`.
inline void keys_from(const std::uint64_t* list, std::uint32_t n, std::uint32_t from,
                      const std::uint64_t*& begin, const std::uint64_t*& end) {
  begin = lower_bound_key(list, n, arc_key(from, 0));
  end = from == 0xFFFFFFFFu ? list + n
                            : lower_bound_key(begin, static_cast<std::uint32_t>(list + n - begin),
                                              arc_key(from + 1, 0));
}

inline bool contains_key(const std::uint64_t* list, std::uint32_t n, std::uint64_t k) {
  const std::uint64_t* p = lower_bound_key(list, n, k);
  return p != list + n && *p == k;
}

}  // namespace kg
