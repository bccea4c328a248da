#include "core/pose/point_grid.h"

#include <algorithm>
#include <cmath>

namespace kg {

namespace {

int cells(int pixels, float cell) {
  return std::max(1, static_cast<int>(std::ceil(static_cast<float>(pixels) / cell)));
}

}  // namespace

void PointGrid::reserve(int max_points, int max_width, int max_height, float cell) {
  head_.reserve(static_cast<std::size_t>(cells(max_width, cell)) *
                static_cast<std::size_t>(cells(max_height, cell)));
  next_.reserve(static_cast<std::size_t>(max_points));
}

void PointGrid::build(const Keypoint* keypoints, int n, int width, int height, float cell) {
  points_ = keypoints;
  cell_ = cell;
  cols_ = cells(width, cell);
  rows_ = cells(height, cell);
  head_.assign(static_cast<std::size_t>(cols_) * static_cast<std::size_t>(rows_), -1);
  next_.assign(static_cast<std::size_t>(n), -1);
  for (int i = 0; i < n; ++i) {
    const int cx = std::clamp(static_cast<int>(keypoints[i].x / cell), 0, cols_ - 1);
    const int cy = std::clamp(static_cast<int>(keypoints[i].y / cell), 0, rows_ - 1);
    next_[i] = head_[cy * cols_ + cx];
    head_[cy * cols_ + cx] = i;
  }
}

int PointGrid::nearest(Point2f p, float radius) const {
  if (!(std::isfinite(p.x) && std::isfinite(p.y))) return -1;
  const float fx = p.x / cell_, fy = p.y / cell_;
  if (fx < -1.f || fy < -1.f || fx > static_cast<float>(cols_) + 1.f ||
      fy > static_cast<float>(rows_) + 1.f)
    return -1;
  const int cx = static_cast<int>(std::floor(fx)), cy = static_cast<int>(std::floor(fy));
  int best = -1;
  float best_d2 = radius * radius;
  for (int y = std::max(0, cy - 1); y <= std::min(rows_ - 1, cy + 1); ++y) {
    for (int x = std::max(0, cx - 1); x <= std::min(cols_ - 1, cx + 1); ++x) {
      for (int i = head_[y * cols_ + x]; i >= 0; i = next_[i]) {
        const float dx = points_[i].x - p.x, dy = points_[i].y - p.y;
        const float d2 = dx * dx + dy * dy;
        if (d2 < best_d2) {
          best_d2 = d2;
          best = i;
        }
      }
    }
  }
  return best;
}

}  // namespace kg
