// Scene keypoint sampling (paper section 5): a maximal subset of keypoints
// in which no two are closer than `min_distance` in Chebyshev distance,
// max(|dx|, |dy|). Keypoints are visited in a random order (paper) or
// strongest first; each is kept unless a kept one is too close.
#pragma once

#include <cstdint>
#include <vector>

#include "core/rng.h"
#include "keygraph/types.h"

namespace kg {

class SeparatedSampler {
 public:
  // Fills `selected` with indices into keypoints[0..n). `rng` == nullptr
  // visits keypoints in the given order (callers pass them strongest first).
  void sample(const Keypoint* keypoints, int n, float min_distance, Rng* rng,
              std::vector<int>& selected);

 private:
  std::vector<int> order_;
  std::vector<int> cell_head_;  // grid of cell size min_distance: first kept index
  std::vector<int> cell_next_;  // next kept index in the same cell
};

inline float chebyshev(Point2f a, Point2f b) {
  const float dx = a.x > b.x ? a.x - b.x : b.x - a.x;
  const float dy = a.y > b.y ? a.y - b.y : b.y - a.y;
  return dx > dy ? dx : dy;
}

}  // namespace kg
