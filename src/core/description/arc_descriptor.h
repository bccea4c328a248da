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

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/description/arc_types.h"
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

// DescriptorParams::subpixel_profiles: `length` (>= 2) samples evenly
// spaced from a to b, both ends included, each the sum of three bilinear
// samples, on the segment and +-parallel_offset pixels perpendicular to it.
// Positions and weights are integers in 1/16 pixel (a and b rounded to
// that), so out (256 times the three pixels' sum) is exact on any core, and
// b -> a gives the reversed profile. False (out unspecified) when a sample
// needs a pixel outside the image or a and b round to one point.
bool subpixel_profile(ImageView blurred, Point2f a, Point2f b, int parallel_offset, int length,
                      std::int32_t* out);

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
bool subpixel_arc_descriptor(ImageView blurred, Point2f a, Point2f b,
                             const DescriptorParams& params, ArcDescriptor& out);
template <class Vector>
bool arc_descriptor(ImageView blurred, Point2f a, Point2f b, const DescriptorParams& params,
                    Vector& scratch, ArcDescriptor& out) {
  out.fill(0.f);
  if (params.subpixel_profiles != 0) return subpixel_arc_descriptor(blurred, a, b, params, out);
  if (!mean_profile(blurred, a, b, params.parallel_offset, scratch)) return false;
  return descriptor_from_samples(scratch.data(), static_cast<int>(scratch.size()), params, out);
}

// --- Fixed point (DescriptorParams::encoding int16 and int8) ------------------
// The same descriptor in integer arithmetic, for cores where that is faster
// and so that the quantised descriptor is computed exactly, not rounded
// twice: the profile's pixel sums (3 times the mean), linear resampling
// with the weights' common denominator kept, the 3-coefficient DFT with
// Q28 cos/sin on exact mean deviations, and round(scale * c / |c|). The
// float path is the reference (tests/core/test_arc_descriptor.cpp).

// Sums of the three parallel pixels per step (profile_samples() of them).
bool profile_sums(ImageView blurred, Point2f a, Point2f b, int parallel_offset, std::int32_t* out);

// resample_linear() times (length - 1), exactly.
void resample_linear_fixed(const std::int32_t* in, int n, std::int32_t* out, int length);

// The quantised descriptor (components round(scale * c), c unit-norm) of a
// resampled profile of length 30 (the paper's l; other lengths use the
// float path). out gets kDescriptorSize values, unused ones zero. False for
// a flat profile.
bool fixed_descriptor(const std::int32_t* profile, int length, int coefficients, std::int32_t scale,
                      std::int32_t* out);

// The fixed-point descriptor of the arc a -> b at `scale` (32767 or 127),
// into out[kDescriptorSize]; `scratch` holds the pixel sums (std::vector or
// WorkVector of int32). False as arc_descriptor() is, or when
// params.profile_length is not 30.
template <class Vector>
bool arc_descriptor_fixed(ImageView blurred, Point2f a, Point2f b, const DescriptorParams& params,
                          std::int32_t scale, Vector& scratch, std::int32_t* out) {
  for (int i = 0; i < kDescriptorSize; ++i) out[i] = 0;
  if (params.profile_length != 30) return false;
  if (params.subpixel_profiles != 0) {
    scratch.resize(30);
    return subpixel_profile(blurred, a, b, params.parallel_offset, 30, scratch.data()) &&
           fixed_descriptor(scratch.data(), 30, params.coefficients, scale, out);
  }
  const int n = profile_samples(blurred, a, b, params.parallel_offset);
  if (n < 2) return false;
  scratch.resize(static_cast<std::size_t>(n) + 30);
  if (!profile_sums(blurred, a, b, params.parallel_offset, scratch.data())) return false;
  std::int32_t* resampled = scratch.data() + n;
  resample_linear_fixed(scratch.data(), n, resampled, 30);
  return fixed_descriptor(resampled, 30, params.coefficients, scale, out);
}

// Whether arcs are described in fixed point for this encoding (int16 and
// int8, at the paper's profile length).
inline bool uses_fixed_point(const DescriptorParams& params) {
  return params.encoding != DescriptorEncoding::kFloat32 && params.profile_length == 30;
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
