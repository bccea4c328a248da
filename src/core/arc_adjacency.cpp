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

}  // namespace kg
