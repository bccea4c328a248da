// Uniform grid over a frame's keypoints for nearest-neighbour look-ups
// within a small radius (guided matching after a pose is found).
#pragma once

#include <vector>

#include "keygraph/types.h"

namespace kg {

class PointGrid {
 public:
  // Indexes keypoints[0..n) of a width x height frame with square cells of
  // `cell` pixels. Buffers are reused between frames.
  void build(const Keypoint* keypoints, int n, int width, int height, float cell);
  // Index of the keypoint nearest to p within `radius` (<= cell), or -1.
  int nearest(Point2f p, float radius) const;

 private:
  const Keypoint* points_ = nullptr;
  int cols_ = 0;
  int rows_ = 0;
  float cell_ = 1.f;
  std::vector<int> head_;
  std::vector<int> next_;
};

}  // namespace kg
