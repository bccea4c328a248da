// Scene keypoint sampling (paper section 5): a maximal subset of keypoints
// in which no two are closer than `min_distance` in Chebyshev distance,
// max(|dx|, |dy|). Keypoints are visited in a random order (paper) or
// strongest first; each is kept unless a kept one is too close.
#pragma once

#include <cstdint>
#include <vector>

#include "core/support/rng.h"
#include "core/support/workspace.h"
#include "keygraph/types.h"

namespace kg {

class SeparatedSampler {
 public:
  explicit SeparatedSampler(std::pmr::memory_resource* memory = std::pmr::get_default_resource())
      : order_(memory), cell_head_(memory), cell_next_(memory) {}

  // Sizes the buffers for up to max_keypoints keypoints inside a
  // max_width x max_height frame: sample() then allocates nothing (keypoints
  // outside the frame only make the grid's cells coarser).
  void reserve(int max_keypoints, int max_width, int max_height, float min_distance);

  // Fills `selected` with indices into keypoints[0..n). `rng` == nullptr
  // visits keypoints in the given order (callers pass them strongest first).
  // `selected` needs room for n indices.
  void sample(const Keypoint* keypoints, int n, float min_distance, Rng* rng,
              WorkVector<int>& selected);
  void sample(const Keypoint* keypoints, int n, float min_distance, Rng* rng,
              std::vector<int>& selected);

 private:
  WorkVector<int> order_;
  WorkVector<int> cell_head_;  // grid of cell size >= min_distance: first kept index
  WorkVector<int> cell_next_;  // next kept index in the same cell
  std::size_t max_cells_ = 4096 * 4096;
};

inline float chebyshev(Point2f a, Point2f b) {
  const float dx = a.x > b.x ? a.x - b.x : b.x - a.x;
  const float dy = a.y > b.y ? a.y - b.y : b.y - a.y;
  return dx > dy ? dx : dy;
}

}  // namespace kg
