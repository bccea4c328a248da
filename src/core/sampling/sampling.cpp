#include "core/sampling/sampling.h"

#include <algorithm>
#include <cmath>

namespace kg {

namespace {

int grid_cells(float extent, float cell) {
  return static_cast<int>(std::min(4095.f, extent / cell)) + 1;
}

}  // namespace

void SeparatedSampler::reserve(int max_keypoints, int max_width, int max_height,
                               float min_distance) {
  const float cell = std::max(min_distance, 1e-3f);
  max_cells_ = static_cast<std::size_t>(grid_cells(static_cast<float>(max_width), cell)) *
               static_cast<std::size_t>(grid_cells(static_cast<float>(max_height), cell));
  order_.reserve(static_cast<std::size_t>(max_keypoints));
  cell_next_.reserve(static_cast<std::size_t>(max_keypoints));
  cell_head_.reserve(max_cells_);
}

void SeparatedSampler::sample(const Keypoint* keypoints, int n, float min_distance, Rng* rng,
                              std::vector<int>& selected) {
  WorkVector<int> out;
  sample(keypoints, n, min_distance, rng, out);
  selected.assign(out.begin(), out.end());
}

void SeparatedSampler::sample(const Keypoint* keypoints, int n, float min_distance, Rng* rng,
                              WorkVector<int>& selected) {
  selected.clear();
  if (n <= 0) return;
  order_.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) order_[i] = i;
  if (rng != nullptr) {
    for (int i = n - 1; i > 0; --i) {
      const int j = static_cast<int>(rng->uniform(static_cast<std::uint32_t>(i + 1)));
      std::swap(order_[i], order_[j]);
    }
  }
  float min_x = keypoints[0].x, min_y = keypoints[0].y, max_x = min_x, max_y = min_y;
  for (int i = 1; i < n; ++i) {
    min_x = std::min(min_x, keypoints[i].x);
    max_x = std::max(max_x, keypoints[i].x);
    min_y = std::min(min_y, keypoints[i].y);
    max_y = std::max(max_y, keypoints[i].y);
  }
  // With cell size >= min_distance only the 3x3 neighbouring cells can hold
  // a conflicting point. Cells are capped so huge coordinates stay bounded:
  // at most 4096 a side, and at most the reserved count (coarser cells).
  float cell = std::max(min_distance, 1e-3f);
  int gw = grid_cells(max_x - min_x, cell), gh = grid_cells(max_y - min_y, cell);
  while (static_cast<std::size_t>(gw) * static_cast<std::size_t>(gh) > max_cells_) {
    cell *= 1.5f;
    gw = grid_cells(max_x - min_x, cell);
    gh = grid_cells(max_y - min_y, cell);
  }
  const float cell_w = std::max(cell, (max_x - min_x) / static_cast<float>(gw) + 1e-3f);
  const float cell_h = std::max(cell, (max_y - min_y) / static_cast<float>(gh) + 1e-3f);
  cell_head_.assign(static_cast<std::size_t>(gw) * static_cast<std::size_t>(gh), -1);
  cell_next_.assign(static_cast<std::size_t>(n), -1);
  for (int idx : order_) {
    const Keypoint& k = keypoints[idx];
    const int cx = std::min(gw - 1, static_cast<int>((k.x - min_x) / cell_w));
    const int cy = std::min(gh - 1, static_cast<int>((k.y - min_y) / cell_h));
    bool free = true;
    for (int y = std::max(0, cy - 1); free && y <= std::min(gh - 1, cy + 1); ++y) {
      for (int x = std::max(0, cx - 1); free && x <= std::min(gw - 1, cx + 1); ++x) {
        for (int j = cell_head_[y * gw + x]; j >= 0; j = cell_next_[j]) {
          if (chebyshev({k.x, k.y}, {keypoints[j].x, keypoints[j].y}) < min_distance) {
            free = false;
            break;
          }
        }
      }
    }
    if (!free) continue;
    cell_next_[idx] = cell_head_[cy * gw + cx];
    cell_head_[cy * gw + cx] = idx;
    selected.push_back(idx);
  }
}

}  // namespace kg
