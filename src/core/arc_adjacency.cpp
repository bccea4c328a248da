#include "core/arc_adjacency.h"

#include <algorithm>

namespace kg {

void ArcAdjacency::build(const ModelIndex& index, bool fill) {
  const std::uint32_t keypoints = index.keypoint_count();
  const std::uint32_t arcs = index.arc_count();
  row_begin_.reserve(static_cast<std::size_t>(keypoints) + 1);
  entries_.reserve(arcs);
  if (!fill) return;
  row_begin_.assign(static_cast<std::size_t>(keypoints) + 1, 0);
  for (std::uint32_t slot = 0; slot < arcs; ++slot) ++row_begin_[index.arc(slot).from + 1];
  for (std::uint32_t k = 0; k < keypoints; ++k) row_begin_[k + 1] += row_begin_[k];
  entries_.resize(arcs);
  // Fill each row from its end (row_begin_[k + 1] counts down to row_begin_[k]).
  WorkVector<std::uint32_t>& next = row_begin_;
  for (std::uint32_t slot = arcs; slot-- > 0;) {
    const ModelArc arc = index.arc(slot);
    entries_[--next[arc.from + 1]] = static_cast<std::uint64_t>(arc.to) << 32 | slot;
  }
  // next[k + 1] is now row k's begin: shift the offsets back into place.
  for (std::uint32_t k = 0; k < keypoints; ++k) row_begin_[k] = row_begin_[k + 1];
  row_begin_[keypoints] = arcs;
  for (std::uint32_t k = 0; k < keypoints; ++k)
    std::sort(entries_.begin() + row_begin_[k], entries_.begin() + row_begin_[k + 1]);
}

void ArcAdjacency::find(const std::uint32_t* from, const std::uint32_t* to, int n,
                        const std::uint64_t** begin, const std::uint64_t** end) const {
  const std::uint64_t* base[kBatch];
  std::uint32_t length[kBatch];
  std::uint64_t key[kBatch];
  std::uint32_t longest = 0;
  for (int i = 0; i < n; ++i) {
    base[i] = entries_.data() + row_begin_[from[i]];
    length[i] = row_begin_[from[i] + 1] - row_begin_[from[i]];
    end[i] = base[i] + length[i];
    key[i] = static_cast<std::uint64_t>(to[i]) << 32;
    longest = std::max(longest, length[i]);
#if defined(__GNUC__)
    __builtin_prefetch(base[i] + length[i] / 2);
#endif
  }
  // Lower bounds by conditional moves: each step halves every range still
  // longer than one entry.
  while (longest > 1) {
    longest = 0;
    for (int i = 0; i < n; ++i) {
      const std::uint32_t len = length[i];
      if (len <= 1) continue;
      const std::uint32_t half = len / 2;
      base[i] = base[i][half] < key[i] ? base[i] + half : base[i];
      length[i] = len - half;
#if defined(__GNUC__)
      __builtin_prefetch(base[i] + length[i] / 2);  // the next step's probe
#endif
      longest = std::max(longest, length[i]);
    }
  }
  for (int i = 0; i < n; ++i) {
    const std::uint64_t* p = base[i];
    if (length[i] == 1 && *p < key[i]) ++p;
    begin[i] = p;
    while (p != end[i] && (*p >> 32) == to[i]) ++p;
    end[i] = p;
  }
}

}  // namespace kg
