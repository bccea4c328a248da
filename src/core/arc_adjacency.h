// The model arcs leaving each model keypoint, for direct look-ups of one
// arc between two given keypoints (graph.complete_circuits): per keypoint,
// its out-arcs' (to, tree slot) sorted by `to`, in compressed rows. Derived
// from the index when a Detector is built (8 bytes per model arc, 4 per
// keypoint, from the Detector's workspace); a frame only reads it.
#pragma once

#include <cstdint>

#include "core/workspace.h"
#include "keygraph/model_index.h"

namespace kg {

class ArcAdjacency {
 public:
  explicit ArcAdjacency(std::pmr::memory_resource* memory) : row_begin_(memory), entries_(memory) {}

  // Reserves the rows for `index` and, when `fill`, fills them (false: the
  // Detector's measuring pass, which only reserves).
  void build(const ModelIndex& index, bool fill);

  // The entries (to << 32 | slot) of the stored arcs from[i] -> to[i], for
  // i < n (at most kBatch): [begin[i], end[i]). The n binary searches run in
  // lock step, each step's next probe prefetched, so their cache
  // misses overlap instead of queueing one behind another.
  static constexpr int kBatch = 32;
  void find(const std::uint32_t* from, const std::uint32_t* to, int n, const std::uint64_t** begin,
            const std::uint64_t** end) const;

 private:
  WorkVector<std::uint32_t> row_begin_;  // keypoint_count + 1 offsets into entries_
  WorkVector<std::uint64_t> entries_;    // to << 32 | slot, each row sorted
};

}  // namespace kg
