#include "core/image/upsample.h"

#include <algorithm>

namespace kg {

void upsample2x(ImageView src, Plane<std::uint8_t>& dst) {
  const int w = src.width, h = src.height;
  dst.resize(2 * w, 2 * h);
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* c = src.row(y);
    // Output row 2y lies a quarter pixel above source row y, 2y + 1 below.
    const std::uint8_t* near_row[2] = {src.row(std::max(y - 1, 0)),
                                       src.row(std::min(y + 1, h - 1))};
    for (int dy = 0; dy < 2; ++dy) {
      const std::uint8_t* n = near_row[dy];
      std::uint8_t* out = dst.row(2 * y + dy);
      for (int x = 0; x < w; ++x) {
        const int l = std::max(x - 1, 0), r = std::min(x + 1, w - 1);
        const int centre = 3 * c[x] + n[x];  // vertical 3/4, 1/4
        const int left = 3 * c[l] + n[l];
        const int right = 3 * c[r] + n[r];
        out[2 * x] = static_cast<std::uint8_t>((3 * centre + left + 8) >> 4);
        out[2 * x + 1] = static_cast<std::uint8_t>((3 * centre + right + 8) >> 4);
      }
    }
  }
}

Homography homography_from_upsampled(const Homography& h) {
  // [0.5 0 -0.25; 0 0.5 -0.25; 0 0 1] H: frame = (upsampled - 0.5) / 2.
  Homography out = h;
  for (int c = 0; c < 3; ++c) {
    out[c] = 0.5 * h[c] - 0.25 * h[6 + c];
    out[3 + c] = 0.5 * h[3 + c] - 0.25 * h[6 + c];
  }
  return out;
}

Homography homography_to_upsampled(const Homography& h) {
  // [2 0 0.5; 0 2 0.5; 0 0 1] H: upsampled = 2 frame + 0.5.
  Homography out = h;
  for (int c = 0; c < 3; ++c) {
    out[c] = 2.0 * h[c] + 0.5 * h[6 + c];
    out[3 + c] = 2.0 * h[3 + c] + 0.5 * h[6 + c];
  }
  return out;
}

}  // namespace kg
