// Small value types shared by every stage.
#pragma once

#include <array>
#include <cstdint>

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

// Number of Fourier coefficients kept per arc (paper: m = 3), so an arc
// descriptor has 2 * kMaxCoefficients numbers (real and imaginary parts).
inline constexpr int kMaxCoefficients = 3;
inline constexpr int kDescriptorSize = 2 * kMaxCoefficients;
using ArcDescriptor = std::array<float, kDescriptorSize>;
// The same descriptor quantised for storage and search
// (DescriptorParams::encoding): each component times 32767 or 127, rounded.
using ArcDescriptorI16 = std::array<std::int16_t, kDescriptorSize>;
using ArcDescriptorI8 = std::array<std::int8_t, kDescriptorSize>;

// What the model index's search tree stores per arc: the descriptor, then
// the arc's scale attributes ln(length / sigma) at its start and at its end
// (core/description/arc_attributes.h), in the same encoding.
inline constexpr int kArcAttributes = 2;
inline constexpr int kSearchDims = kDescriptorSize + kArcAttributes;
using ArcSearchPoint = std::array<float, kSearchDims>;
using ArcSearchPointI16 = std::array<std::int16_t, kSearchDims>;
using ArcSearchPointI8 = std::array<std::int8_t, kSearchDims>;

}  // namespace kg
