#include "core/selection/arc_adjacency.h"

#include <algorithm>

namespace kg {

void ArcAdjacency::build(const ModelIndex& index, bool fill) {
  const std::uint32_t keypoints = index.keypoint_count();
  const std::uint32_t arcs = index.arc_count();
  // Each row padded to whole blocks: at most kBlock - 1 entries more a keypoint.
  const std::size_t capacity = std::size_t{arcs} + std::size_t{keypoints} * (kBlock - 1);
  row_begin_.reserve(std::size_t{keypoints} + 1);
  entries_.reserve(capacity);
  block_to_.reserve(capacity / kBlock);
  if (!fill) return;
  row_begin_.assign(std::size_t{keypoints} + 1, 0);
  for (std::uint32_t slot = 0; slot < arcs; ++slot) ++row_begin_[index.arc(slot).from + 1];
  // row_begin_[k + 1] becomes the end of row k's entries (its block-aligned
  // start plus its length), from where the fill below counts down.
  std::size_t start = 0;
  for (std::uint32_t k = 0; k < keypoints; ++k) {
    const std::size_t length = row_begin_[k + 1];
    row_begin_[k + 1] = start + length;
    start += (length + kBlock - 1) / kBlock * kBlock;
  }
  const std::size_t total = start;
  entries_.assign(total, kPadding);
  WorkVector<std::size_t>& next = row_begin_;
  for (std::uint32_t slot = arcs; slot-- > 0;) {
    const ModelArc arc = index.arc(slot);
    entries_[--next[arc.from + 1]] = static_cast<std::uint64_t>(arc.to) << 32 | slot;
  }
  // next[k + 1] is now row k's begin: shift the offsets back into place.
  for (std::uint32_t k = 0; k < keypoints; ++k) row_begin_[k] = row_begin_[k + 1];
  row_begin_[keypoints] = total;
  // The padding is above every key, so it stays at the rows' ends.
  for (std::uint32_t k = 0; k < keypoints; ++k)
    std::sort(entries_.begin() + static_cast<std::ptrdiff_t>(row_begin_[k]),
              entries_.begin() + static_cast<std::ptrdiff_t>(row_begin_[k + 1]));
  block_to_.resize(total / kBlock);
  for (std::size_t b = 0; b < block_to_.size(); ++b)
    block_to_[b] = static_cast<std::uint32_t>(entries_[b * kBlock] >> 32);
}

void ArcAdjacency::find(const std::uint32_t* from, const std::uint32_t* to, int n,
                        const std::uint64_t** begin, const std::uint64_t** end) const {
  const std::uint32_t* first[kBatch];  // the row's block starts
  std::size_t blocks[kBatch];
  for (int i = 0; i < n; ++i) {
    const std::size_t row = row_begin_[from[i]];
    first[i] = block_to_.data() + row / kBlock;
    blocks[i] = (row_begin_[from[i] + 1] - row) / kBlock;
    end[i] = entries_.data() + row_begin_[from[i] + 1];
#if defined(__GNUC__)
    if (blocks[i] > 0) {
      __builtin_prefetch(first[i]);
      if (blocks[i] > 16) __builtin_prefetch(first[i] + 16);
    }
#endif
  }
  // The block where the entries not below to[i] start: the last one whose
  // first `to` is below it (they may start at the next block's first
  // entry), or the row's first. Conditional moves.
  for (int i = 0; i < n; ++i) {
    const std::uint32_t* base = first[i];
    std::size_t length = blocks[i];
    while (length > 1) {
      const std::size_t half = length / 2;
      base = base[half] < to[i] ? base + half : base;
      length -= half;
    }
    if (blocks[i] == 0) {
      begin[i] = end[i];
      continue;
    }
    const auto block = static_cast<std::size_t>(base - block_to_.data());
    begin[i] = entries_.data() + block * kBlock;
#if defined(__GNUC__)
    __builtin_prefetch(begin[i]);
    __builtin_prefetch(begin[i] + kBlock / 2);
#endif
  }
  for (int i = 0; i < n; ++i) {
    const std::uint64_t* p = begin[i];
    if (p == end[i]) continue;
    // Entries below to[i] in the block (the padding is above every key),
    // then the run of to[i].
    const std::uint64_t key = static_cast<std::uint64_t>(to[i]) << 32;
    std::uint32_t below = 0;
    for (std::uint32_t x = 0; x < kBlock; ++x) below += static_cast<std::uint32_t>(p[x] < key);
    p += below;
    begin[i] = p;
    while (p != end[i] && (*p >> 32) == to[i]) ++p;
    end[i] = p;
  }
}

}  // namespace kg
