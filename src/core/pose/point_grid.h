// Uniform grid over a frame's keypoints for nearest-neighbour look-ups
// within a small radius (guided matching after a pose is found).
#pragma once

#include <vector>

#include "core/support/workspace.h"
#include "keygraph/types.h"

namespace kg {

class PointGrid {
 public:
  explicit PointGrid(std::pmr::memory_resource* memory = std::pmr::get_default_resource())
      : head_(memory), next_(memory) {}
  // Sizes the buffers for up to max_points in a max_width x max_height frame.
  void reserve(int max_points, int max_width, int max_height, float cell);
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
  WorkVector<int> head_;
  WorkVector<int> next_;
};

}  // namespace kg
