// Scale attributes of an arc (GraphParams::max_scale_error): ln(L / sigma)
// at its start and at its end, with L the arc's Euclidean length and sigma
// each keypoint's detector scale. Under a local similarity both lengths and
// scales change by the same factor, so the attributes of a model arc and of
// its scene arc agree; the model index stores them beside each descriptor
// and a radius query asks for both within max_scale_error of the scene
// arc's (|ln(L_s / L_m) - ln(sigma_s / sigma_m)| <= max_scale_error at each
// end). They are stored divided by kAttributeRange, in the descriptor's
// domain, so one quantisation serves both.
#pragma once

#include <cmath>

#include "keygraph/types.h"

namespace kg {

inline constexpr float kAttributeRange = 8.f;  // attributes beyond +-8 saturate

// Fills out[0], out[1] (already divided by kAttributeRange). False when a
// scale is unknown (<= 0) or the arc is degenerate; out is then zero.
inline bool arc_attributes(Point2f a, Point2f b, float sigma_a, float sigma_b, float* out) {
  out[0] = out[1] = 0.f;
  const float length = std::hypot(b.x - a.x, b.y - a.y);
  if (!(sigma_a > 0.f && sigma_b > 0.f && length > 0.f)) return false;
  out[0] = std::log(length / sigma_a) / kAttributeRange;
  out[1] = std::log(length / sigma_b) / kAttributeRange;
  return true;
}

// The search point of an arc: its descriptor, then its attributes.
inline ArcSearchPoint search_point(const ArcDescriptor& d, const float* attributes) {
  ArcSearchPoint p{};
  for (int i = 0; i < kDescriptorSize; ++i) p[i] = d[i];
  for (int i = 0; i < kArcAttributes; ++i) p[kDescriptorSize + i] = attributes[i];
  return p;
}

}  // namespace kg
