// The model arcs leaving each model keypoint, for direct look-ups of one
// arc between two given keypoints (graph.complete_circuits): per keypoint,
// its out-arcs' (to, tree slot) sorted by `to`, in compressed rows padded
// to blocks of 16 entries, and the first `to` of every block. Derived from
// the index when a Detector is built (8.25 bytes per model arc, and per
// keypoint 8 for its row offset and room for 15 entries of padding, from
// the Detector's workspace); a frame only reads it.
#pragma once

#include <cstdint>

#include "core/support/workspace.h"
#include "keygraph/model_index.h"

namespace kg {

class ArcAdjacency {
 public:
  explicit ArcAdjacency(std::pmr::memory_resource* memory)
      : row_begin_(memory), entries_(memory), block_to_(memory) {}

  // Reserves the rows for `index` and, when `fill`, fills them (false: the
  // Detector's measuring pass, which only reserves).
  void build(const ModelIndex& index, bool fill);

  // The entries (to << 32 | slot) of the stored arcs from[i] -> to[i], for
  // i < n (at most kBatch): [begin[i], end[i]). Rows are hundreds of
  // entries long with tilted views (a binary search over one was a chain
  // of about nine cache misses): each look-up searches its row's block
  // starts (a few cache lines), then scans one block. The n look-ups run
  // in stages, each stage prefetching the lines the next one reads, so
  // their misses overlap instead of queueing one behind another.
  static constexpr int kBatch = 32;
  static constexpr std::uint32_t kBlock = 16;  // entries per block (two cache lines)
  void find(const std::uint32_t* from, const std::uint32_t* to, int n, const std::uint64_t** begin,
            const std::uint64_t** end) const;

 private:
  // Pads a row's last block: above every key, and its `to` (2^32 - 1) is
  // no keypoint id (their count is a uint32).
  static constexpr std::uint64_t kPadding = ~std::uint64_t{0};
  WorkVector<std::size_t> row_begin_;   // keypoint_count + 1 offsets into entries_, block starts
  WorkVector<std::uint64_t> entries_;   // to << 32 | slot, each row sorted, padded with kPadding
  WorkVector<std::uint32_t> block_to_;  // the `to` of each block's first entry
};

}  // namespace kg
