// Small value types shared by every stage.
#pragma once

#include <array>

namespace kg {

struct Point2f {
  float x = 0.f;
  float y = 0.f;
};

// A detected keypoint in image pixels. `scale` is the detector's
// characteristic scale (sigma in pixels, 0 when unknown); `response` its
// strength, larger is stronger.
struct Keypoint {
  float x = 0.f;
  float y = 0.f;
  float scale = 0.f;
  float response = 0.f;
};

// Row-major 3x3 homography mapping model pixels to scene pixels:
// [x_s, y_s, w]^T = H [x_m, y_m, 1]^T.
using Homography = std::array<double, 9>;

inline Point2f apply(const Homography& h, Point2f p) {
  const double w = h[6] * p.x + h[7] * p.y + h[8];
  return {static_cast<float>((h[0] * p.x + h[1] * p.y + h[2]) / w),
          static_cast<float>((h[3] * p.x + h[4] * p.y + h[5]) / w)};
}

// Number of Fourier coefficients an arc descriptor can keep (paper: m = 3):
// the upper bound of DescriptorParams::coefficients.
inline constexpr int kMaxCoefficients = 3;

}  // namespace kg
