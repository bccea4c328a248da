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

// Samples of the mean profile from a to b: the Chebyshev length of the
// rounded endpoints plus one; 0 when a sampled pixel lies outside the image
// or a == b.
int profile_samples(ImageView blurred, Point2f a, Point2f b, int parallel_offset);

// Mean of the three parallel profiles from a to b into out[0 ..
// profile_samples()). Returns false (writing nothing) when
// profile_samples() is 0.
bool mean_profile(ImageView blurred, Point2f a, Point2f b, int parallel_offset, float* out);

// The same into a vector resized to profile_samples() (std::vector or
// WorkVector: within its capacity this allocates nothing).
template <class Vector>
bool mean_profile(ImageView blurred, Point2f a, Point2f b, int parallel_offset, Vector& profile) {
  const int n = profile_samples(blurred, a, b, parallel_offset);
  if (n == 0) return false;
  profile.resize(static_cast<std::size_t>(n));
  return mean_profile(blurred, a, b, parallel_offset, profile.data());
}

// Linear resampling of `in` (n >= 2 samples) onto `length` samples whose
// first and last coincide with in's first and last.
void resample_linear(const float* in, int n, float* out, int length);

// Descriptor from an already resampled profile of `length` samples. Returns
// false if the profile is flat (all kept coefficients zero).
bool descriptor_from_profile(const float* profile, int length, int coefficients,
                             ArcDescriptor& out);

// Descriptor of n >= 2 profile samples: resampled to params.profile_length,
// then descriptor_from_profile(). False for bad parameters or a flat profile.
bool descriptor_from_samples(const float* samples, int n, const DescriptorParams& params,
                             ArcDescriptor& out);

// Full descriptor of the arc a -> b. Returns false when the arc leaves the
// image, is degenerate or its profile is flat. `scratch` is reused storage
// for the profile (a std::vector or WorkVector).
template <class Vector>
bool arc_descriptor(ImageView blurred, Point2f a, Point2f b, const DescriptorParams& params,
                    Vector& scratch, ArcDescriptor& out) {
  out.fill(0.f);
  if (!mean_profile(blurred, a, b, params.parallel_offset, scratch)) return false;
  return descriptor_from_samples(scratch.data(), static_cast<int>(scratch.size()), params, out);
}

inline float squared_distance(const ArcDescriptor& p, const ArcDescriptor& q) {
  float s = 0.f;
  for (int i = 0; i < kDescriptorSize; ++i) {
    const float d = p[i] - q[i];
    s += d * d;
  }
  return s;
}

}  // namespace kg
