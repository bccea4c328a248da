// Scale attributes of an arc (GraphParams::max_scale_error): ln(L / sigma)
// at its start and at its end, with L the arc's Euclidean length and sigma
// each keypoint's detector scale. Under a local similarity both lengths and
// scales change by the same factor, so the attributes of a model arc and of
// its scene arc agree; the model index stores them beside each descriptor
// and a radius query asks for both within max_scale_error of the scene
// arc's (|ln(L_s / L_m) - ln(sigma_s / sigma_m)| <= max_scale_error at each
// end).
//
// Attributes live on a grid of 1/16 natural-log units, as integers in
// [-127, 127], in every encoding (the float32 tree holds them as floats):
// the box is a whole number of steps, so float and integer indexes make the
// same attribute decisions, and quantising the descriptor is the only
// difference between them.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "core/description/arc_types.h"
#include "core/description/descriptor_encoding.h"
#include "keygraph/params.h"
#include "keygraph/types.h"

namespace kg {

inline constexpr float kAttributeSteps = 16.f;   // grid steps per natural-log unit
inline constexpr float kAttributeLimit = 127.f;  // +-7.9 log units; beyond saturates

// Fills out[0], out[1] with the grid values. False when a scale is unknown
// (<= 0) or the arc is degenerate; out is then zero.
inline bool arc_attributes(Point2f a, Point2f b, float sigma_a, float sigma_b, float* out) {
  out[0] = out[1] = 0.f;
  const float length = std::hypot(b.x - a.x, b.y - a.y);
  if (!(sigma_a > 0.f && sigma_b > 0.f && length > 0.f)) return false;
  const float ln[2] = {std::log(length / sigma_a), std::log(length / sigma_b)};
  for (int i = 0; i < 2; ++i) {
    const float v = std::round(ln[i] * kAttributeSteps);
    out[i] = v > kAttributeLimit ? kAttributeLimit : v < -kAttributeLimit ? -kAttributeLimit : v;
  }
  return true;
}

// The box half-width of max_scale_error in grid steps (0: no box).
inline std::int32_t attribute_box(const GraphParams& graph) {
  return static_cast<std::int32_t>(std::floor(graph.max_scale_error * kAttributeSteps + 1e-4f));
}

// The search point of an arc: its descriptor, then its attributes.
inline ArcSearchPoint search_point(const ArcDescriptor& d, const float* attributes) {
  ArcSearchPoint p{};
  for (int i = 0; i < kDescriptorSize; ++i) p[i] = d[i];
  for (int i = 0; i < kArcAttributes; ++i) p[kDescriptorSize + i] = attributes[i];
  return p;
}

// A search point in the domain of T: the descriptor quantised (integer
// encodings) or as is (float), the attributes as the grid integers they are.
template <class T>
inline std::array<T, kSearchDims> encode_point(const ArcSearchPoint& p) {
  std::array<T, kSearchDims> out{};
  for (int i = 0; i < kDescriptorSize; ++i) {
    if constexpr (std::is_same_v<T, float>) {
      out[i] = p[i];
    } else {
      out[i] = quantise_component<T>(p[i]);
    }
  }
  for (int i = kDescriptorSize; i < kSearchDims; ++i) out[i] = static_cast<T>(p[i]);
  return out;
}

}  // namespace kg
