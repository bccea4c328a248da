// Dissimilarity of two vertex descriptors (Params::descriptor.vertex_descriptor,
// paper section 7): the Euclidean distance between the descriptors scaled
// to unit length. Descriptors are kVertexDescriptorSize bytes (OpenCV's
// 8-bit SIFT); the index stores them as computed and the unit scaling
// happens here, through precomputed inverse norms.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "keygraph/params.h"

namespace kg {

inline std::uint32_t vertex_dot(const std::uint8_t* a, const std::uint8_t* b) {
  std::uint32_t sum = 0;
  for (int i = 0; i < kVertexDescriptorSize; ++i)
    sum += static_cast<std::uint32_t>(a[i]) * static_cast<std::uint32_t>(b[i]);
  return sum;
}

// 1 / |a|, and 0 for the all-zero descriptor (flat patch), which so comes
// out orthogonal to everything (distance sqrt(2)).
inline float vertex_inverse_norm(const std::uint8_t* a) {
  const std::uint32_t n2 = vertex_dot(a, a);
  return n2 == 0 ? 0.f : static_cast<float>(1.0 / std::sqrt(static_cast<double>(n2)));
}

// Squared distance between a / |a| and b / |b|, from their inverse norms.
inline float vertex_distance2(const std::uint8_t* a, float inverse_norm_a, const std::uint8_t* b,
                              float inverse_norm_b) {
  const float cosine = static_cast<float>(vertex_dot(a, b)) * inverse_norm_a * inverse_norm_b;
  return std::max(0.f, 2.f - 2.f * cosine);
}

inline float vertex_distance(const std::uint8_t* a, const std::uint8_t* b) {
  return std::sqrt(vertex_distance2(a, vertex_inverse_norm(a), b, vertex_inverse_norm(b)));
}

}  // namespace kg
