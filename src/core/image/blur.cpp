#include "core/image/blur.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <type_traits>

#include "core/support/simd_dispatch.h"

#if defined(KG_NEON_FLOAT)
#include <arm_neon.h>
#endif
#if defined(KG_DISPATCH_AVX2)
#include <immintrin.h>
#endif

namespace kg {
namespace {

// Kernels are truncated at this radius (sigma above ~170 px, far beyond any
// use here); the bound keeps the kernel on the stack so blurring never
// allocates.
constexpr int kMaxRadius = 512;

// Half of a symmetric kernel: w[0] is the centre tap, w[i] the taps at +-i.
struct Kernel {
  std::array<float, kMaxRadius + 1> w;
  int radius = 0;
};

void make_kernel(float sigma, Kernel& k) {
  k.radius = blur_radius(sigma);
  const double inv_two_var = 1.0 / (2.0 * static_cast<double>(sigma) * sigma);
  double sum = 1.0;
  for (int i = 1; i <= k.radius; ++i) sum += 2.0 * std::exp(-i * i * inv_two_var);
  k.w[0] = static_cast<float>(1.0 / sum);
  for (int i = 1; i <= k.radius; ++i)
    k.w[i] = static_cast<float>(std::exp(-i * i * inv_two_var) / sum);
}

// Vertical pass for output row y: rows come from `row(i)` (clamped, so the
// border rows are replicated). Taps outer, pixels inner, so the inner loop is
// a contiguous multiply-add the compiler vectorises.
template <class T, class RowFn>
KG_ALWAYS_INLINE void vertical_row(RowFn row, int y, int w, int h, const Kernel& k, float* out) {
  const T* c = row(y);
  const float k0 = k.w[0];
  for (int x = 0; x < w; ++x) out[x] = k0 * static_cast<float>(c[x]);
  int i = 1;
  for (; i + 3 <= k.radius; i += 4) {
    const T* a0 = row(std::max(y - i, 0));
    const T* b0 = row(std::min(y + i, h - 1));
    const T* a1 = row(std::max(y - i - 1, 0));
    const T* b1 = row(std::min(y + i + 1, h - 1));
    const T* a2 = row(std::max(y - i - 2, 0));
    const T* b2 = row(std::min(y + i + 2, h - 1));
    const T* a3 = row(std::max(y - i - 3, 0));
    const T* b3 = row(std::min(y + i + 3, h - 1));
    const float ka = k.w[i];
    const float kb = k.w[i + 1];
    const float kc = k.w[i + 2];
    const float kd = k.w[i + 3];
    for (int x = 0; x < w; ++x)
      out[x] += (ka * (static_cast<float>(a0[x]) + static_cast<float>(b0[x])) +
                 kb * (static_cast<float>(a1[x]) + static_cast<float>(b1[x]))) +
                (kc * (static_cast<float>(a2[x]) + static_cast<float>(b2[x])) +
                 kd * (static_cast<float>(a3[x]) + static_cast<float>(b3[x])));
  }
  for (; i + 1 <= k.radius; i += 2) {
    const T* a0 = row(std::max(y - i, 0));
    const T* b0 = row(std::min(y + i, h - 1));
    const T* a1 = row(std::max(y - i - 1, 0));
    const T* b1 = row(std::min(y + i + 1, h - 1));
    const float ka = k.w[i];
    const float kb = k.w[i + 1];
    for (int x = 0; x < w; ++x)
      out[x] += ka * (static_cast<float>(a0[x]) + static_cast<float>(b0[x])) +
                kb * (static_cast<float>(a1[x]) + static_cast<float>(b1[x]));
  }
  if (i <= k.radius) {
    const T* a = row(std::max(y - i, 0));
    const T* b = row(std::min(y + i, h - 1));
    const float ki = k.w[i];
    for (int x = 0; x < w; ++x)
      out[x] += ki * (static_cast<float>(a[x]) + static_cast<float>(b[x]));
  }
}

// Horizontal pass of one row. `in` points at pixel 0 of a row padded with
// `radius` replicated pixels on both sides, so no read needs a clamp; `out`
// must not alias it.
KG_ALWAYS_INLINE void horizontal_row(const float* in, int w, const Kernel& k, float* out) {
  const int r = k.radius;
  const float k0 = k.w[0];
  for (int x = 0; x < w; ++x) out[x] = k0 * in[x];
  int i = 1;
  for (; i + 3 <= r; i += 4) {
    const float ka = k.w[i];
    const float kb = k.w[i + 1];
    const float kc = k.w[i + 2];
    const float kd = k.w[i + 3];
    for (int x = 0; x < w; ++x)
      out[x] += (ka * (in[x - i] + in[x + i]) + kb * (in[x - i - 1] + in[x + i + 1])) +
                (kc * (in[x - i - 2] + in[x + i + 2]) + kd * (in[x - i - 3] + in[x + i + 3]));
  }
  for (; i + 1 <= r; i += 2) {
    const float ka = k.w[i];
    const float kb = k.w[i + 1];
    for (int x = 0; x < w; ++x)
      out[x] += ka * (in[x - i] + in[x + i]) + kb * (in[x - i - 1] + in[x + i + 1]);
  }
  if (i <= r) {
    const float ki = k.w[i];
    for (int x = 0; x < w; ++x) out[x] += ki * (in[x - i] + in[x + i]);
  }
}

// Rounds the 8-bit blur's row of w values to pixels.
void round_row(const float* in, int w, std::uint8_t* d) {
  for (int x = 0; x < w; ++x) {
    // Normalised weights keep the sum within [0, 255] up to rounding.
    const int v = static_cast<int>(in[x] + 0.5f);
    d[x] = static_cast<std::uint8_t>(std::clamp(v, 0, 255));
  }
}

// Replicates the end pixels of the row [0, w) into its `radius` padding.
KG_ALWAYS_INLINE void pad_row(float* row, int w, int radius) {
  std::fill(row - radius, row, row[0]);
  std::fill(row + w, row + w + radius, row[w - 1]);
}

// The vector passes below (NEON, AVX2) sum each pixel over all taps in a
// register (the portable loops add each group of taps into memory), in the
// portable loops' order, so the same values bit for bit. The radii of the
// frame's blurs (3 to 8) get their own copies, with the taps unrolled and
// the rows and weights in registers.
constexpr int kMaxFixedRadius = 10;

// Calls f(std::integral_constant<int, R>) for radius R when R is at most
// kMaxFixedRadius, else f(std::integral_constant<int, 0>): any radius.
template <int R = 1, class F>
KG_ALWAYS_INLINE void with_radius(int radius, F f) {
  if constexpr (R <= kMaxFixedRadius) {
    if (radius == R) return f(std::integral_constant<int, R>{});
    with_radius<R + 1>(radius, f);
  } else {
    f(std::integral_constant<int, 0>{});
  }
}

// The sum over the taps of `radius` as the portable loops compute it, for
// one pixel (V = float) or a vector of them: `at(offset)` loads the pixels
// `offset` taps away on one side (-) or the other (+); w[i] is the weight
// of taps +-i.
template <class V, class Load>
KG_ALWAYS_INLINE V taps(Load at, const float* w, int radius) {
  V v = w[0] * at(0);
  const auto pair = [&](int i) { return w[i] * (at(-i) + at(i)); };
  int i = 1;
  for (; i + 3 <= radius; i += 4) v += (pair(i) + pair(i + 1)) + (pair(i + 2) + pair(i + 3));
  for (; i + 1 <= radius; i += 2) v += pair(i) + pair(i + 1);
  if (i <= radius) v += pair(i);
  return v;
}

#if defined(KG_NEON_FLOAT)
// The passes with NEON intrinsics, 4 pixels at a time.

inline float32x4_t load4(const float* p) {
  return vld1q_f32(p);
}
inline float32x4_t load4(const std::uint8_t* p) {
  std::uint32_t four;
  std::memcpy(&four, p, sizeof four);
  const uint16x8_t wide = vmovl_u8(vreinterpret_u8_u32(vdup_n_u32(four)));
  return vcvtq_f32_u32(vmovl_u16(vget_low_u16(wide)));
}
// k * (a + b), one tap pair.
inline float32x4_t tap(const float32x4_t& a, const float32x4_t& b, float k) {
  return vmulq_n_f32(vaddq_f32(a, b), k);
}

// taps() for 4 pixels.
template <class Load>
KG_ALWAYS_INLINE float32x4_t taps4(Load at, const float* w, int radius) {
  float32x4_t acc = vmulq_n_f32(at(0), w[0]);
  int i = 1;
  for (; i + 3 <= radius; i += 4) {
    const float32x4_t s0 = tap(at(-i), at(i), w[i]);
    const float32x4_t s1 = tap(at(-i - 1), at(i + 1), w[i + 1]);
    const float32x4_t s2 = tap(at(-i - 2), at(i + 2), w[i + 2]);
    const float32x4_t s3 = tap(at(-i - 3), at(i + 3), w[i + 3]);
    acc = vaddq_f32(acc, vaddq_f32(vaddq_f32(s0, s1), vaddq_f32(s2, s3)));
  }
  for (; i + 1 <= radius; i += 2)
    acc = vaddq_f32(acc, vaddq_f32(tap(at(-i), at(i), w[i]), tap(at(-i - 1), at(i + 1), w[i + 1])));
  if (i <= radius) acc = vaddq_f32(acc, tap(at(-i), at(i), w[i]));
  return acc;
}

// The vector steps of the passes for vector_blur_u8/_float below.
struct Neon {
  // vertical_row's values. centre[i], i in [-radius, radius]: the clamped
  // source row of tap i.
  template <int R, class T>
  static void vertical(const T* const* centre, int w, const Kernel& k, float* out) {
    const int radius = R > 0 ? R : k.radius;
    // Local copies (registers when R is fixed): stores to `out` cannot
    // change them.
    const T* rows[2 * (R > 0 ? R : kMaxRadius) + 1];
    float weights[(R > 0 ? R : kMaxRadius) + 1];
    for (int i = -radius; i <= radius; ++i) rows[radius + i] = centre[i];
    for (int i = 0; i <= radius; ++i) weights[i] = k.w[static_cast<std::size_t>(i)];
    int x = 0;
    for (; x + 4 <= w; x += 4)
      vst1q_f32(out + x,
                taps4([&](int i) { return load4(rows[radius + i] + x); }, weights, radius));
    for (; x < w; ++x)
      out[x] = taps<float>([&](int i) { return static_cast<float>(rows[radius + i][x]); }, weights,
                           radius);
  }

  // horizontal_row's values, the same way.
  template <int R>
  static void horizontal(const float* in, int w, const Kernel& k, float* out) {
    const int radius = R > 0 ? R : k.radius;
    float weights[(R > 0 ? R : kMaxRadius) + 1];
    for (int i = 0; i <= radius; ++i) weights[i] = k.w[static_cast<std::size_t>(i)];
    int x = 0;
    for (; x + 4 <= w; x += 4)
      vst1q_f32(out + x, taps4([&](int i) { return vld1q_f32(in + x + i); }, weights, radius));
    for (; x < w; ++x) out[x] = taps<float>([&](int i) { return in[x + i]; }, weights, radius);
  }

  // The 8-bit blur's rounding of one row (round_row's values); the
  // saturating narrowings are the clamp.
  static void round(const float* in, int w, std::uint8_t* d) {
    int x = 0;
    for (; x + 8 <= w; x += 8) {
      const float32x4_t half = vdupq_n_f32(0.5f);
      const int32x4_t lo = vcvtq_s32_f32(vaddq_f32(vld1q_f32(in + x), half));
      const int32x4_t hi = vcvtq_s32_f32(vaddq_f32(vld1q_f32(in + x + 4), half));
      vst1_u8(d + x, vqmovn_u16(vcombine_u16(vqmovun_s32(lo), vqmovun_s32(hi))));
    }
    round_row(in + x, w - x, d + x);
  }
};
#endif

#if defined(KG_DISPATCH_AVX2)
// The passes for AVX2, 8 pixels at a time, written with GCC/Clang vectors
// (the same type as __m256): one ymm register in these functions, all
// compiled for AVX2 (no lambdas: those would not be, and could not inline
// the loads).
typedef float Float8 __attribute__((vector_size(32)));

KG_TARGET_AVX2 KG_ALWAYS_INLINE Float8 load8(const float* p) {
  Float8 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
// Widened with intrinsics: __builtin_convertvector of 8 bytes to floats
// compiles to one conversion per byte.
KG_TARGET_AVX2 KG_ALWAYS_INLINE Float8 load8(const std::uint8_t* p) {
  std::int64_t eight;
  std::memcpy(&eight, p, sizeof eight);
  return _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_cvtsi64_si128(eight)));
}

// The pixels of a tap: rows[i] + x (vertical pass) or in[i] (horizontal).
template <class T>
struct TapRows {
  const T* const* rows;
  int x;
  KG_TARGET_AVX2 KG_ALWAYS_INLINE Float8 at(int i) const { return load8(rows[i] + x); }
};
struct TapShifts {
  const float* in;
  KG_TARGET_AVX2 KG_ALWAYS_INLINE Float8 at(int i) const { return load8(in + i); }
};

// taps() for 8 pixels, the same operations in the same order.
template <class Source>
KG_TARGET_AVX2 KG_ALWAYS_INLINE Float8 taps8(const Source& s, const float* w, int radius) {
  Float8 v = w[0] * s.at(0);
  int i = 1;
  for (; i + 3 <= radius; i += 4)
    v += (w[i] * (s.at(-i) + s.at(i)) + w[i + 1] * (s.at(-i - 1) + s.at(i + 1))) +
         (w[i + 2] * (s.at(-i - 2) + s.at(i + 2)) + w[i + 3] * (s.at(-i - 3) + s.at(i + 3)));
  for (; i + 1 <= radius; i += 2)
    v += w[i] * (s.at(-i) + s.at(i)) + w[i + 1] * (s.at(-i - 1) + s.at(i + 1));
  if (i <= radius) v += w[i] * (s.at(-i) + s.at(i));
  return v;
}

struct Avx2 {
  template <int R, class T>
  KG_TARGET_AVX2 static void vertical(const T* const* centre, int w, const Kernel& k, float* out) {
    const int radius = R > 0 ? R : k.radius;
    const T* rows[2 * (R > 0 ? R : kMaxRadius) + 1];
    float weights[(R > 0 ? R : kMaxRadius) + 1];
    for (int i = -radius; i <= radius; ++i) rows[radius + i] = centre[i];
    for (int i = 0; i <= radius; ++i) weights[i] = k.w[static_cast<std::size_t>(i)];
    int x = 0;
    for (; x + 8 <= w; x += 8) {
      const Float8 v = taps8(TapRows<T>{rows + radius, x}, weights, radius);
      std::memcpy(out + x, &v, sizeof v);
    }
    for (; x < w; ++x)
      out[x] = taps<float>([&](int i) { return static_cast<float>(rows[radius + i][x]); }, weights,
                           radius);
  }

  template <int R>
  KG_TARGET_AVX2 static void horizontal(const float* in, int w, const Kernel& k, float* out) {
    const int radius = R > 0 ? R : k.radius;
    float weights[(R > 0 ? R : kMaxRadius) + 1];
    for (int i = 0; i <= radius; ++i) weights[i] = k.w[static_cast<std::size_t>(i)];
    int x = 0;
    for (; x + 8 <= w; x += 8) {
      const Float8 v = taps8(TapShifts{in + x}, weights, radius);
      std::memcpy(out + x, &v, sizeof v);
    }
    for (; x < w; ++x) out[x] = taps<float>([&](int i) { return in[x + i]; }, weights, radius);
  }

  KG_TARGET_AVX2 static void round(const float* in, int w, std::uint8_t* d) {
    int x = 0;
    for (; x + 8 <= w; x += 8) {
      // Truncated toward zero as static_cast<int> does; the saturating
      // packs are the clamp.
      const __m256i v = _mm256_cvttps_epi32(load8(in + x) + 0.5f);
      const __m128i words =
          _mm_packus_epi32(_mm256_castsi256_si128(v), _mm256_extracti128_si256(v, 1));
      const std::int64_t eight = _mm_cvtsi128_si64(_mm_packus_epi16(words, words));
      std::memcpy(d + x, &eight, sizeof eight);
    }
    round_row(in + x, w - x, d + x);
  }
};
#endif

#if defined(KG_NEON_FLOAT) || defined(KG_DISPATCH_AVX2)
// The image loops around the vector steps of `Lanes` (Neon, Avx2).
template <class Lanes, class T, class RowFn>
void vector_vertical_row(RowFn row, int y, int w, int h, const Kernel& k, float* out) {
  const T* rows[2 * kMaxRadius + 1];
  const T** centre = rows + k.radius;
  for (int i = -k.radius; i <= k.radius; ++i) centre[i] = row(std::clamp(y + i, 0, h - 1));
  with_radius(k.radius,
              [&](auto r) { Lanes::template vertical<decltype(r)::value, T>(centre, w, k, out); });
}

template <class Lanes>
void vector_horizontal_row(const float* in, int w, const Kernel& k, float* out) {
  with_radius(k.radius,
              [&](auto r) { Lanes::template horizontal<decltype(r)::value>(in, w, k, out); });
}

template <class Lanes>
void vector_blur_u8(ImageView src, const Kernel& k, Plane<std::uint8_t>& dst, float* vert,
                    float* horz) {
  const int w = src.width;
  const int h = src.height;
  const auto row = [&src](int y) { return src.row(y); };
  for (int y = 0; y < h; ++y) {
    vector_vertical_row<Lanes, std::uint8_t>(row, y, w, h, k, vert);
    pad_row(vert, w, k.radius);
    vector_horizontal_row<Lanes>(vert, w, k, horz);
    Lanes::round(horz, w, dst.row(y));
  }
}

template <class Lanes>
void vector_blur_float(const Plane<float>& src, const Kernel& k, Plane<float>& dst, int y0, int y1,
                       float* vert) {
  const int w = src.width();
  const int h = src.height();
  const auto row = [&src](int y) { return src.row(y); };
  for (int y = y0; y < y1; ++y) {
    vector_vertical_row<Lanes, float>(row, y, w, h, k, vert);
    pad_row(vert, w, k.radius);
    vector_horizontal_row<Lanes>(vert, w, k, dst.row(y));
  }
}
#endif

// The portable image loops: the baseline (SSE2 on x86-64) and the scalar level.
void blur_u8_portable(ImageView src, const Kernel& k, Plane<std::uint8_t>& dst, float* vert,
                      float* horz) {
  const int w = src.width;
  const int h = src.height;
  const auto row = [&src](int y) { return src.row(y); };
  for (int y = 0; y < h; ++y) {
    vertical_row<std::uint8_t>(row, y, w, h, k, vert);
    pad_row(vert, w, k.radius);
    horizontal_row(vert, w, k, horz);
    round_row(horz, w, dst.row(y));
  }
}

// Row by row (vertical into a padded buffer row, then horizontal straight
// into dst) so the source rows in use stay in cache.
void blur_float_portable(const Plane<float>& src, const Kernel& k, Plane<float>& dst, int y0,
                         int y1, float* vert) {
  const int w = src.width();
  const int h = src.height();
  const auto row = [&src](int y) { return src.row(y); };
  for (int y = y0; y < y1; ++y) {
    vertical_row<float>(row, y, w, h, k, vert);
    pad_row(vert, w, k.radius);
    horizontal_row(vert, w, k, dst.row(y));
  }
}

void blur_u8(ImageView src, const Kernel& k, Plane<std::uint8_t>& dst, float* vert, float* horz) {
#if defined(KG_DISPATCH_AVX2)
  if (simd_level() == SimdLevel::kAvx2) return vector_blur_u8<Avx2>(src, k, dst, vert, horz);
#elif defined(KG_NEON_FLOAT)
  if (simd_level() != SimdLevel::kScalar) return vector_blur_u8<Neon>(src, k, dst, vert, horz);
#endif
  blur_u8_portable(src, k, dst, vert, horz);
}

void blur_float(const Plane<float>& src, const Kernel& k, Plane<float>& dst, int y0, int y1,
                float* vert) {
#if defined(KG_DISPATCH_AVX2)
  if (simd_level() == SimdLevel::kAvx2) return vector_blur_float<Avx2>(src, k, dst, y0, y1, vert);
#elif defined(KG_NEON_FLOAT)
  if (simd_level() != SimdLevel::kScalar) return vector_blur_float<Neon>(src, k, dst, y0, y1, vert);
#endif
  blur_float_portable(src, k, dst, y0, y1, vert);
}

}  // namespace

int blur_radius(float sigma) {
  const float r = std::ceil(3.f * sigma);
  return !(r > 0.f) ? 0 : r >= static_cast<float>(kMaxRadius) ? kMaxRadius : static_cast<int>(r);
}

void gaussian_blur(ImageView src, float sigma, Plane<std::uint8_t>& dst, Plane<float>& scratch) {
  if (src.empty()) {
    dst.resize(0, 0);
    return;
  }
  const int w = src.width;
  const int h = src.height;
  dst.resize(w, h);
  if (!(sigma > 0.f)) {
    for (int y = 0; y < h; ++y) std::memcpy(dst.row(y), src.row(y), static_cast<std::size_t>(w));
    return;
  }
  Kernel k;
  make_kernel(sigma, k);
  // Two row buffers: the padded vertical result, then the horizontal one
  // before rounding.
  const int padded = w + 2 * k.radius;
  scratch.resize(padded, 2);
  float* vert = scratch.row(0) + k.radius;
  float* horz = scratch.row(1);
  blur_u8(src, k, dst, vert, horz);
}

void gaussian_blur(const Plane<float>& src, float sigma, Plane<float>& dst, Plane<float>& scratch) {
  const int w = src.width();
  const int h = src.height();
  if (w <= 0 || h <= 0) {
    dst.resize(0, 0);
    return;
  }
  dst.resize(w, h);
  gaussian_blur_rows(src, sigma, dst, 0, h, scratch);
}

void gaussian_blur_rows(const Plane<float>& src, float sigma, Plane<float>& dst, int y0, int y1,
                        Plane<float>& scratch) {
  const int w = src.width();
  y0 = std::max(y0, 0);
  y1 = std::min(y1, src.height());
  if (w <= 0 || y0 >= y1) return;
  if (!(sigma > 0.f)) {
    for (int y = y0; y < y1; ++y)
      std::memcpy(dst.row(y), src.row(y), static_cast<std::size_t>(w) * sizeof(float));
    return;
  }
  Kernel k;
  make_kernel(sigma, k);
  scratch.resize(w + 2 * k.radius, 1);
  float* vert = scratch.row(0) + k.radius;
  blur_float(src, k, dst, y0, y1, vert);
}

}  // namespace kg
