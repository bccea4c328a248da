// Arc descriptor encodings (DescriptorParams::encoding): the scale of each
// integer domain, quantisation of a float descriptor into it, and the
// similarity radius scaled into it. Model descriptors (builder) and scene
// descriptors (selection) go through the same quantise(), so both sides of
// a comparison are rounded alike.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "core/description/arc_types.h"
#include "core/params/param_names.h"
#include "keygraph/params.h"
#include "keygraph/types.h"

namespace kg {

// Components are multiplied by this before rounding (1 for float32).
inline constexpr std::int32_t encoding_scale(DescriptorEncoding e) {
  return e == DescriptorEncoding::kInt16 ? 32767 : e == DescriptorEncoding::kInt8 ? 127 : 1;
}

// Bytes per stored tree point (descriptor and attributes).
inline constexpr std::size_t encoded_point_size(DescriptorEncoding e) {
  return e == DescriptorEncoding::kInt16  ? sizeof(ArcSearchPointI16)
         : e == DescriptorEncoding::kInt8 ? sizeof(ArcSearchPointI8)
                                          : sizeof(ArcSearchPoint);
}

inline const char* encoding_name(DescriptorEncoding e) {
  const char* name = enum_name(e);
  return name != nullptr ? name : "unknown";
}

// round(v * scale), saturated to [-scale, scale]; NaN gives 0. Rounding is
// half away from zero (std::lround), in double so every platform agrees.
template <class T>
inline T quantise_component(float v) {
  constexpr auto scale = static_cast<double>(std::numeric_limits<T>::max());
  const double x = static_cast<double>(v) * scale;
  if (!(x == x)) return T{0};
  if (x >= scale) return std::numeric_limits<T>::max();
  if (x <= -scale) return static_cast<T>(-std::numeric_limits<T>::max());
  return static_cast<T>(std::lround(x));
}

template <class T, std::size_t N>
inline std::array<T, N> quantise(const std::array<float, N>& d) {
  std::array<T, N> q{};
  for (std::size_t i = 0; i < N; ++i) q[i] = quantise_component<T>(d[i]);
  return q;
}
// The squared similarity radius in the integer domain of `e`:
// ceil(radius^2 * scale^2) with radius^2 rounded to float as the float path
// rounds it, so that for an integer squared distance d, d < result exactly
// when d / scale^2 < radius^2. Exact integer arithmetic in 64 bits; false
// when radius is not finite and positive or the result exceeds `limit` (the
// largest squared distance the search type holds).
inline bool scaled_radius2(float radius, DescriptorEncoding e, std::int64_t limit,
                           std::int64_t& out) {
  if (!(std::isfinite(radius) && radius > 0.f)) return false;
  const float r2 = radius * radius;  // the float path compares against this value
  if (!std::isfinite(r2) || r2 <= 0.f) return false;
  // r2 = mantissa * 2^exponent with a 24-bit integer mantissa.
  int exponent = 0;
  const float fraction = std::frexp(r2, &exponent);
  const auto mantissa = static_cast<std::uint64_t>(std::ldexp(fraction, 24));
  exponent -= 24;
  const auto scale = static_cast<std::uint64_t>(encoding_scale(e));
  const std::uint64_t product = mantissa * scale * scale;  // < 2^24 * 2^30
  std::uint64_t result = 0;
  if (exponent >= 0) {
    if (exponent >= 63 || product > (std::numeric_limits<std::uint64_t>::max() >> exponent))
      return false;
    result = product << exponent;
  } else if (exponent <= -63) {
    result = 1;  // 0 < r2 * scale^2 < 1
  } else {
    const std::uint64_t unit = std::uint64_t{1} << -exponent;
    result = product / unit + (product % unit != 0 ? 1 : 0);
  }
  if (limit < 0 || result > static_cast<std::uint64_t>(limit)) return false;
  out = static_cast<std::int64_t>(result);
  return true;
}

}  // namespace kg
