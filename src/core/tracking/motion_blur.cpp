#include "core/tracking/motion_blur.h"

#include <algorithm>
#include <cmath>

namespace kg {

void blur_along(const std::uint8_t* src, int width, int height, float dx, float dy,
                std::uint8_t* dst) {
  const float length = std::min(std::hypot(dx, dy), 64.f);
  const float scale = length > 0.f ? length / std::hypot(dx, dy) : 0.f;
  dx *= scale;
  dy *= scale;
  // A sample per pixel of the segment, at least two.
  const int n = std::max(2, static_cast<int>(std::ceil(length)) + 1);
  const float inv = 1.f / static_cast<float>(n);
  const auto at = [&](int x, int y) {
    x = std::clamp(x, 0, width - 1);
    y = std::clamp(y, 0, height - 1);
    return static_cast<float>(src[static_cast<std::size_t>(y) * width + x]);
  };
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      float sum = 0.f;
      for (int k = 0; k < n; ++k) {
        const float t = -0.5f + static_cast<float>(k) / static_cast<float>(n - 1);
        const float sx = static_cast<float>(x) + t * dx, sy = static_cast<float>(y) + t * dy;
        const float fx = std::floor(sx), fy = std::floor(sy);
        const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
        const float ax = sx - fx, ay = sy - fy;
        sum += (1.f - ay) * ((1.f - ax) * at(ix, iy) + ax * at(ix + 1, iy)) +
               ay * ((1.f - ax) * at(ix, iy + 1) + ax * at(ix + 1, iy + 1));
      }
      dst[static_cast<std::size_t>(y) * width + x] =
          static_cast<std::uint8_t>(std::clamp(sum * inv + 0.5f, 0.f, 255.f));
    }
  }
}

}  // namespace kg
