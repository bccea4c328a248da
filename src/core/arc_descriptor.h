// Arc descriptors (paper section 6): the mean of three parallel Bresenham
// intensity profiles from vertex a to vertex b on the blurred image,
// resampled to `profile_length` samples by linear interpolation, then DFT
// coefficients 1..m (F(0) dropped for brightness invariance) divided by
// their L2 norm (contrast invariance). Component order: a1, b1, a2, b2, ...
// with F(x) = a_x + i b_x = sum_y f(y) exp(-2 pi i x y / l).
//
// The parallel profiles are the central Bresenham line shifted by
// +-parallel_offset pixels along the line's minor axis (y for lines that are
// more horizontal than vertical, x otherwise). Endpoints are rounded to the
// nearest pixel. Components past 2*m are set to zero.
#pragma once

#include <vector>

#include "keygraph/image.h"
#include "keygraph/params.h"
#include "keygraph/types.h"

namespace kg {

// Mean of the three parallel profiles from a to b; `profile` gets
// Chebyshev(a, b) + 1 samples. Returns false when any sampled pixel lies
// outside the image or a == b.
bool mean_profile(ImageView blurred, Point2f a, Point2f b, int parallel_offset,
                  std::vector<float>& profile);

// Linear resampling of `in` (n >= 2 samples) onto `length` samples whose
// first and last coincide with in's first and last.
void resample_linear(const float* in, int n, float* out, int length);

// Descriptor from an already resampled profile of `length` samples. Returns
// false if the profile is flat (all kept coefficients zero).
bool descriptor_from_profile(const float* profile, int length, int coefficients,
                             ArcDescriptor& out);

// Full descriptor of the arc a -> b. Returns false when the arc leaves the
// image, is degenerate or its profile is flat. `scratch` is reused storage.
bool arc_descriptor(ImageView blurred, Point2f a, Point2f b, const DescriptorParams& params,
                    std::vector<float>& scratch, ArcDescriptor& out);

inline float squared_distance(const ArcDescriptor& p, const ArcDescriptor& q) {
  float s = 0.f;
  for (int i = 0; i < kDescriptorSize; ++i) {
    const float d = p[i] - q[i];
    s += d * d;
  }
  return s;
}

}  // namespace kg
