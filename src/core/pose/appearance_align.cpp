#include "core/pose/appearance_align.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "core/support/simd_dispatch.h"

#if defined(KG_DISPATCH_AVX2)
#include <immintrin.h>
#endif
#if defined(KG_NEON_FLOAT)
#include <arm_neon.h>
#endif

namespace kg {

namespace {

constexpr int kParams = 8;                   // homography parameters (h33 fixed)
constexpr int kMaxIterations = 10;           // Gauss-Newton steps per level
constexpr double kConverged = 0.1;           // largest corner step, level pixels
constexpr double kMinInside = 0.7;           // share of the level that must be in the frame
constexpr int kMinHalfLongEdge = 16;         // smaller half levels carry too little
constexpr std::size_t kMinScorePixels = 64;  // fewer make a correlation meaningless
constexpr double kMinVariance = 1.0;         // grey levels squared: flat below
// Frame pixels per appearance pixel below which the half level is scored.
constexpr double kScoreOnHalfBelow = 0.6;
constexpr int kMaxSubsamples = 2;  // per axis, where the frame is finer than the level
constexpr double kSelected = 0.3;  // share of the pixels the Gauss-Newton steps use
constexpr std::size_t kMinSelected = 200;
constexpr double kTukey = 4.685;           // Tukey's biweight constant (95 % efficiency)
constexpr double kMinResidualScale = 2.0;  // grey levels: the noise floor of the residuals
// Sampling on the workers: a few chunks per thread (a thread that wakes late
// still finds work), none smaller than this many pixels (each run wakes the
// workers, which costs more than sampling a few hundred pixels).
constexpr int kChunksPerThread = 4;
constexpr std::size_t kMinChunkPixels = 256;
// The normal equations on the workers: each thread then sums a share of the
// rows over every pixel (a few hundred instructions each).
constexpr std::size_t kMinNormalPixels = 512;

void multiply(const double a[9], const double b[9], double out[9]) {
  double r[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      r[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
  std::copy(r, r + 9, out);
}

bool invert(const double m[9], double out[9]) {
  const double c0 = m[4] * m[8] - m[5] * m[7];
  const double c1 = m[5] * m[6] - m[3] * m[8];
  const double c2 = m[3] * m[7] - m[4] * m[6];
  const double det = m[0] * c0 + m[1] * c1 + m[2] * c2;
  if (!(std::fabs(det) > 1e-300) || !std::isfinite(det)) return false;
  const double d = 1.0 / det;
  out[0] = c0 * d;
  out[1] = (m[2] * m[7] - m[1] * m[8]) * d;
  out[2] = (m[1] * m[5] - m[2] * m[4]) * d;
  out[3] = c1 * d;
  out[4] = (m[0] * m[8] - m[2] * m[6]) * d;
  out[5] = (m[2] * m[3] - m[0] * m[5]) * d;
  out[6] = c2 * d;
  out[7] = (m[1] * m[6] - m[0] * m[7]) * d;
  out[8] = (m[0] * m[4] - m[1] * m[3]) * d;
  return true;
}

// The level's normalised coordinates (centred, half the long edge = 1,
// which keeps the normal equations well conditioned) -> model pixels.
void level_to_model(int width, int height, float scale_x, float scale_y, double out[9]) {
  const double half_long = 0.5 * std::max(width, height);
  const double sx = scale_x, sy = scale_y;
  out[0] = half_long / sx;
  out[1] = 0.0;
  out[2] = (0.5 * (width - 1) + 0.5) / sx - 0.5;
  out[3] = 0.0;
  out[4] = half_long / sy;
  out[5] = (0.5 * (height - 1) + 0.5) / sy - 0.5;
  out[6] = 0.0;
  out[7] = 0.0;
  out[8] = 1.0;
}

// The frame point of a level's normalised point (x, y) under g. Inlined:
// warp_pixels() calls it for every sample, and a call passes x and y
// through memory (the same operations either way, so the same values).
KG_ALWAYS_INLINE void project(const double g[9], double xn, double yn, double& x, double& y) {
  const double z = 1.0 / (g[6] * xn + g[7] * yn + g[8]);
  x = (g[0] * xn + g[1] * yn + g[2]) * z;
  y = (g[3] * xn + g[4] * yn + g[5]) * z;
}

KG_ALWAYS_INLINE float bilinear(ImageView f, double x, double y) {
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const auto fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
  const std::uint8_t* r0 = f.row(y0) + x0;
  const std::uint8_t* r1 = r0 + f.stride;
  const float top = r0[0] + fx * static_cast<float>(r0[1] - r0[0]);
  const float bottom = r1[0] + fx * static_cast<float>(r1[1] - r1[0]);
  return top + fy * (bottom - top);
}

// Cholesky solve of the 8x8 normal equations (a is overwritten).
bool solve8(double a[kParams][kParams], const double b[kParams], double x[kParams]) {
  for (int j = 0; j < kParams; ++j) {
    double d = a[j][j];
    for (int k = 0; k < j; ++k) d -= a[j][k] * a[j][k];
    if (!(d > 1e-12)) return false;
    a[j][j] = std::sqrt(d);
    for (int i = j + 1; i < kParams; ++i) {
      double s = a[i][j];
      for (int k = 0; k < j; ++k) s -= a[i][k] * a[j][k];
      a[i][j] = s / a[j][j];
    }
  }
  double y[kParams];
  for (int i = 0; i < kParams; ++i) {
    double s = b[i];
    for (int k = 0; k < i; ++k) s -= a[i][k] * y[k];
    y[i] = s / a[i][i];
  }
  for (int i = kParams - 1; i >= 0; --i) {
    double s = y[i];
    for (int k = i + 1; k < kParams; ++k) s -= a[k][i] * x[k];
    x[i] = s / a[i][i];
  }
  return true;
}

// What the normal equations of one Gauss-Newton step sum over: the
// selected pixels' Tukey-weighted residuals and steepest-descent images.
struct NormalTerms {
  const std::uint32_t* selected;
  std::size_t n;
  const std::uint8_t* valid;
  const float* warped;
  const float* t;
  const float* steepest;  // n x kParams
  double gain, mi, mt, cutoff;

  // Selected pixel k's residual e and Tukey weight, false when the pixel is
  // invalid or an outlier (|e| at or past the cutoff). Every normal_rows
  // variant calls this, so they sum the same values.
  bool weighted_residual(std::size_t k, double& e, double& weight) const {
    const std::uint32_t i = selected[k];
    if (!valid[i]) return false;
    e = gain * (warped[i] - mi) - (t[i] - mt);
    if (std::fabs(e) >= cutoff) return false;
    const double r = 1.0 - (e / cutoff) * (e / cutoff);
    weight = r * r;
    return true;
  }
};

#if defined(KG_DISPATCH_AVX2)
// normal_rows()'s sums with AVX2: row j's entries (weight sd[j]) sd[l] four
// at a time (lanes l > j summed too, and left unused), each entry the same
// operations in the same pixel order, so the same values.
template <unsigned Rows>
KG_TARGET_AVX2 void normal_rows_avx2(const NormalTerms& q, double a[kParams][kParams],
                                     double b[kParams]) {
  static_assert(kParams == 8, "two 4-lane halves a row");
  __m256d sa[kParams][2];
  for (auto& row : sa) row[0] = row[1] = _mm256_setzero_pd();
  double sb[kParams] = {};
  for (std::size_t k = 0; k < q.n; ++k) {
    double e, weight;
    if (!q.weighted_residual(k, e, weight)) continue;
    const float* sd = &q.steepest[k * kParams];
    const __m256d low = _mm256_cvtps_pd(_mm_loadu_ps(sd));
    const __m256d high = _mm256_cvtps_pd(_mm_loadu_ps(sd + 4));
#pragma GCC unroll 8
    for (int j = 0; j < kParams; ++j) {
      if (!((Rows >> j) & 1u)) continue;
      const double wj = weight * static_cast<double>(sd[j]);
      sb[j] += wj * e;
      const __m256d w4 = _mm256_set1_pd(wj);
      sa[j][0] = _mm256_add_pd(sa[j][0], _mm256_mul_pd(w4, low));
      if (j >= 4) sa[j][1] = _mm256_add_pd(sa[j][1], _mm256_mul_pd(w4, high));
    }
  }
  for (int j = 0; j < kParams; ++j) {
    if (!((Rows >> j) & 1u)) continue;
    b[j] = sb[j];
    alignas(32) double row[kParams];
    _mm256_store_pd(row, sa[j][0]);
    _mm256_store_pd(row + 4, sa[j][1]);
    for (int l = 0; l <= j; ++l) a[j][l] = row[l];
  }
}
#endif

#if defined(KG_NEON_FLOAT)
// normal_rows()'s sums with AArch64 NEON: row j's entries (weight sd[j])
// sd[l] two at a time (lanes l > j summed too, and left unused), each entry
// the same operations in the same pixel order, so the same values.
template <unsigned Rows>
void normal_rows_neon(const NormalTerms& q, double a[kParams][kParams], double b[kParams]) {
  static_assert(kParams == 8, "four 2-lane quarters a row");
  float64x2_t sa[kParams][4];
  for (auto& row : sa) row[0] = row[1] = row[2] = row[3] = vdupq_n_f64(0.0);
  double sb[kParams] = {};
  for (std::size_t k = 0; k < q.n; ++k) {
    double e, weight;
    if (!q.weighted_residual(k, e, weight)) continue;
    const float* sd = &q.steepest[k * kParams];
    const float32x4_t low = vld1q_f32(sd), high = vld1q_f32(sd + 4);
    const float64x2_t s[4] = {vcvt_f64_f32(vget_low_f32(low)), vcvt_high_f64_f32(low),
                              vcvt_f64_f32(vget_low_f32(high)), vcvt_high_f64_f32(high)};
#pragma GCC unroll 8
    for (int j = 0; j < kParams; ++j) {
      if (!((Rows >> j) & 1u)) continue;
      const double wj = weight * static_cast<double>(sd[j]);
      sb[j] += wj * e;
      const float64x2_t w2 = vdupq_n_f64(wj);
#pragma GCC unroll 4
      for (int h = 0; h <= j / 2; ++h) sa[j][h] = vaddq_f64(sa[j][h], vmulq_f64(w2, s[h]));
    }
  }
  for (int j = 0; j < kParams; ++j) {
    if (!((Rows >> j) & 1u)) continue;
    b[j] = sb[j];
    double row[kParams];
    for (int h = 0; h < 4; ++h) vst1q_f64(row + 2 * h, sa[j][h]);
    for (int l = 0; l <= j; ++l) a[j][l] = row[l];
  }
}
#endif

// Sums the rows of the normal equations in `Rows` (bit j: row j of the
// lower triangle of a and b[j]) over every pixel, in pixel order: each
// entry is the same sum, bit for bit, whichever rows are summed together.
template <unsigned Rows>
void normal_rows(const NormalTerms& q, double a[kParams][kParams], double b[kParams]) {
#if defined(KG_DISPATCH_AVX2)
  if (simd_level() == SimdLevel::kAvx2) return normal_rows_avx2<Rows>(q, a, b);
#endif
#if defined(KG_NEON_FLOAT)
  if (simd_level() != SimdLevel::kScalar) return normal_rows_neon<Rows>(q, a, b);
#endif
  double sa[kParams][kParams] = {};
  double sb[kParams] = {};
  for (std::size_t k = 0; k < q.n; ++k) {
    double e, weight;
    if (!q.weighted_residual(k, e, weight)) continue;
    const float* sd = &q.steepest[k * kParams];
    for (int j = 0; j < kParams; ++j) {
      if (!((Rows >> j) & 1u)) continue;
      sb[j] += weight * sd[j] * e;
      for (int l = 0; l <= j; ++l) sa[j][l] += weight * static_cast<double>(sd[j]) * sd[l];
    }
  }
  for (int j = 0; j < kParams; ++j) {
    if (!((Rows >> j) & 1u)) continue;
    b[j] = sb[j];
    for (int l = 0; l <= j; ++l) a[j][l] = sa[j][l];
  }
}

// The normal equations, their rows split over the workers when there are
// enough pixels. Rows j and 7 - j hold 11 entries together (j + 1 and
// 8 - j in the triangle, one each in b), so pairs of them balance the
// threads; the result does not depend on the split (normal_rows).
void normal_equations(const NormalTerms& q, WorkerPool* workers, double a[kParams][kParams],
                      double b[kParams]) {
  const int threads = workers == nullptr ? 1 : workers->threads();
  if (threads <= 1 || q.n < kMinNormalPixels) {
    normal_rows<0xFFu>(q, a, b);
    return;
  }
  const int groups = threads >= 4 ? 4 : 2;
  auto group = [&](int c, int) {
    if (groups == 2) {
      if (c == 0) normal_rows<0xC3u>(q, a, b);  // rows 0, 1, 6, 7
      if (c == 1) normal_rows<0x3Cu>(q, a, b);  // rows 2 to 5
      return;
    }
    if (c == 0) normal_rows<0x81u>(q, a, b);
    if (c == 1) normal_rows<0x42u>(q, a, b);
    if (c == 2) normal_rows<0x24u>(q, a, b);
    if (c == 3) normal_rows<0x18u>(q, a, b);
  };
  workers->run(groups, group);
}

// The sampling of warp_level(): the level's pixel grid under g.
struct WarpGrid {
  double g[9];
  int w, sub;
  double half_long, cx, cy, step, first, max_x, max_y;
  float weight;
};

#if defined(KG_DISPATCH_AVX2)
// warp_pixels()'s values for 4 pixels at a time with AVX2, the first
// (end - begin) / 4 * 4 of them; returns where the portable loop takes
// over. Each lane is one pixel and goes through its samples in the same
// order with the same operations (double projection, the bilinear read in
// float, the float sum), so the same values; a lane with a sample outside
// the frame reads pixel (0, 0) from then on, its sum unused (the portable
// loop stops there), and all lanes outside end the pixel's samples.
KG_TARGET_AVX2 std::size_t warp_pixels_avx2(const WarpGrid& grid, ImageView frame,
                                            const std::uint32_t* pixels, std::size_t begin,
                                            std::size_t end, std::uint8_t* valid, float* warped) {
  const WarpGrid q = grid;
  const auto w = static_cast<std::uint32_t>(q.w);
  __m256d g[9];
  for (int i = 0; i < 9; ++i) g[i] = _mm256_set1_pd(q.g[i]);
  const __m256d cx = _mm256_set1_pd(q.cx), cy = _mm256_set1_pd(q.cy);
  const __m256d half_long = _mm256_set1_pd(q.half_long), first = _mm256_set1_pd(q.first);
  const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0);
  const __m256d max_x = _mm256_set1_pd(q.max_x), max_y = _mm256_set1_pd(q.max_y);
  const std::ptrdiff_t stride = frame.stride;
  // Pixel offsets in 32-bit lanes (frames of up to 2 GiB).
  if (stride <= 0 || stride * (frame.height + 1) > INT32_MAX) return begin;
  const __m128i stride4 = _mm_set1_epi32(static_cast<std::int32_t>(stride));
  const __m128i low_byte = _mm_set1_epi32(0xFF);
  std::size_t k = begin;
  for (; k + 4 <= end; k += 4) {
    alignas(16) std::int32_t u[4], v[4];
    for (int l = 0; l < 4; ++l) {
      const std::uint32_t i = pixels[k + static_cast<std::size_t>(l)];
      u[l] = static_cast<int>(i % w);
      v[l] = static_cast<int>(i / w);
    }
    const __m256d xn0 = _mm256_add_pd(
        _mm256_div_pd(
            _mm256_sub_pd(_mm256_cvtepi32_pd(_mm_load_si128(reinterpret_cast<const __m128i*>(u))),
                          cx),
            half_long),
        first);
    const __m256d yn0 = _mm256_add_pd(
        _mm256_div_pd(
            _mm256_sub_pd(_mm256_cvtepi32_pd(_mm_load_si128(reinterpret_cast<const __m128i*>(v))),
                          cy),
            half_long),
        first);
    __m256d inside = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
    __m128 sum = _mm_setzero_ps();
    for (int sy = 0; sy < q.sub; ++sy) {
      const __m256d yn = _mm256_add_pd(yn0, _mm256_set1_pd(sy * q.step));
      int sx = 0;
      for (; sx < q.sub; ++sx) {
        const __m256d xn = _mm256_add_pd(xn0, _mm256_set1_pd(sx * q.step));
        // project()
        const __m256d z = _mm256_div_pd(
            one,
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(g[6], xn), _mm256_mul_pd(g[7], yn)), g[8]));
        const __m256d x = _mm256_mul_pd(
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(g[0], xn), _mm256_mul_pd(g[1], yn)), g[2]),
            z);
        const __m256d y = _mm256_mul_pd(
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(g[3], xn), _mm256_mul_pd(g[4], yn)), g[5]),
            z);
        const __m256d in = _mm256_and_pd(
            _mm256_and_pd(_mm256_cmp_pd(x, zero, _CMP_GE_OQ), _mm256_cmp_pd(y, zero, _CMP_GE_OQ)),
            _mm256_and_pd(_mm256_cmp_pd(x, max_x, _CMP_LT_OQ),
                          _mm256_cmp_pd(y, max_y, _CMP_LT_OQ)));
        inside = _mm256_and_pd(inside, in);
        if (_mm256_movemask_pd(inside) == 0) break;
        // bilinear(), at (0, 0) for the lanes outside.
        const __m256d xs = _mm256_and_pd(x, inside), ys = _mm256_and_pd(y, inside);
        const __m128i x0 = _mm256_cvttpd_epi32(xs), y0 = _mm256_cvttpd_epi32(ys);
        const __m128 fx = _mm256_cvtpd_ps(_mm256_sub_pd(xs, _mm256_cvtepi32_pd(x0)));
        const __m128 fy = _mm256_cvtpd_ps(_mm256_sub_pd(ys, _mm256_cvtepi32_pd(y0)));
        // Each lane's two pixel pairs, two bytes at a time (little-endian:
        // the left pixel is the low byte).
        alignas(16) std::int32_t at[4], upper[4], lower[4];
        _mm_store_si128(reinterpret_cast<__m128i*>(at),
                        _mm_add_epi32(_mm_mullo_epi32(y0, stride4), x0));
        for (int l = 0; l < 4; ++l) {
          const std::uint8_t* r0 = frame.data + at[l];
          std::uint16_t a, b;
          std::memcpy(&a, r0, sizeof a);
          std::memcpy(&b, r0 + stride, sizeof b);
          upper[l] = a;
          lower[l] = b;
        }
        const __m128i up = _mm_load_si128(reinterpret_cast<const __m128i*>(upper));
        const __m128i down = _mm_load_si128(reinterpret_cast<const __m128i*>(lower));
        const __m128i a00 = _mm_and_si128(up, low_byte), a01 = _mm_srli_epi32(up, 8);
        const __m128i a10 = _mm_and_si128(down, low_byte), a11 = _mm_srli_epi32(down, 8);
        const __m128 top = _mm_add_ps(_mm_cvtepi32_ps(a00),
                                      _mm_mul_ps(fx, _mm_cvtepi32_ps(_mm_sub_epi32(a01, a00))));
        const __m128 bottom = _mm_add_ps(_mm_cvtepi32_ps(a10),
                                         _mm_mul_ps(fx, _mm_cvtepi32_ps(_mm_sub_epi32(a11, a10))));
        sum = _mm_add_ps(sum, _mm_add_ps(top, _mm_mul_ps(fy, _mm_sub_ps(bottom, top))));
      }
      if (sx < q.sub) break;
    }
    const int in_bits = _mm256_movemask_pd(inside);
    alignas(16) float value[4];
    _mm_store_ps(value, _mm_mul_ps(sum, _mm_set1_ps(q.weight)));
    for (int l = 0; l < 4; ++l) {
      const std::uint32_t i = pixels[k + static_cast<std::size_t>(l)];
      const bool ok = ((in_bits >> l) & 1) != 0;
      valid[i] = ok ? 1 : 0;
      warped[i] = ok ? value[l] : 0.f;
    }
  }
  return k;
}
#endif

#if defined(KG_NEON_FLOAT)
// warp_pixels()'s values for 4 pixels at a time with AArch64 NEON (the
// doubles in two 2-lane halves, the floats in one 4-lane vector), the first
// (end - begin) / 4 * 4 of them; returns where the portable loop takes
// over. Each lane is one pixel and goes through its samples in the same
// order with the same operations (double projection, the bilinear read in
// float, the float sum), so the same values; a lane with a sample outside
// the frame reads pixel (0, 0) from then on, its sum unused (the portable
// loop stops there), and all lanes outside end the pixel's samples.
std::size_t warp_pixels_neon(const WarpGrid& grid, ImageView frame, const std::uint32_t* pixels,
                             std::size_t begin, std::size_t end, std::uint8_t* valid,
                             float* warped) {
  const WarpGrid q = grid;
  const auto w = static_cast<std::uint32_t>(q.w);
  float64x2_t g[9];
  for (int i = 0; i < 9; ++i) g[i] = vdupq_n_f64(q.g[i]);
  const float64x2_t cx = vdupq_n_f64(q.cx), cy = vdupq_n_f64(q.cy);
  const float64x2_t half_long = vdupq_n_f64(q.half_long), first = vdupq_n_f64(q.first);
  const float64x2_t zero = vdupq_n_f64(0.0), one = vdupq_n_f64(1.0);
  const float64x2_t max_x = vdupq_n_f64(q.max_x), max_y = vdupq_n_f64(q.max_y);
  const std::ptrdiff_t stride = frame.stride;
  // Pixel offsets in 32-bit lanes (frames of up to 2 GiB).
  if (stride <= 0 || stride * (frame.height + 1) > INT32_MAX) return begin;
  const int32x4_t stride4 = vdupq_n_s32(static_cast<std::int32_t>(stride));
  const uint32x4_t low_byte = vdupq_n_u32(0xFF);
  std::size_t k = begin;
  for (; k + 4 <= end; k += 4) {
    double u[4], v[4];
    for (int l = 0; l < 4; ++l) {
      const std::uint32_t i = pixels[k + static_cast<std::size_t>(l)];
      u[l] = static_cast<int>(i % w);
      v[l] = static_cast<int>(i / w);
    }
    float64x2_t xn0[2], yn0[2];
    uint64x2_t inside[2];
    for (int h = 0; h < 2; ++h) {
      xn0[h] = vaddq_f64(vdivq_f64(vsubq_f64(vld1q_f64(u + 2 * h), cx), half_long), first);
      yn0[h] = vaddq_f64(vdivq_f64(vsubq_f64(vld1q_f64(v + 2 * h), cy), half_long), first);
      inside[h] = vdupq_n_u64(~std::uint64_t{0});
    }
    float32x4_t sum = vdupq_n_f32(0.f);
    for (int sy = 0; sy < q.sub; ++sy) {
      const float64x2_t dy = vdupq_n_f64(sy * q.step);
      int sx = 0;
      for (; sx < q.sub; ++sx) {
        const float64x2_t dx = vdupq_n_f64(sx * q.step);
        int32x2_t x0[2], y0[2];
        float32x2_t fx[2], fy[2];
        for (int h = 0; h < 2; ++h) {
          const float64x2_t xn = vaddq_f64(xn0[h], dx), yn = vaddq_f64(yn0[h], dy);
          // project()
          const float64x2_t z =
              vdivq_f64(one, vaddq_f64(vaddq_f64(vmulq_f64(g[6], xn), vmulq_f64(g[7], yn)), g[8]));
          const float64x2_t x =
              vmulq_f64(vaddq_f64(vaddq_f64(vmulq_f64(g[0], xn), vmulq_f64(g[1], yn)), g[2]), z);
          const float64x2_t y =
              vmulq_f64(vaddq_f64(vaddq_f64(vmulq_f64(g[3], xn), vmulq_f64(g[4], yn)), g[5]), z);
          const uint64x2_t in = vandq_u64(vandq_u64(vcgeq_f64(x, zero), vcgeq_f64(y, zero)),
                                          vandq_u64(vcltq_f64(x, max_x), vcltq_f64(y, max_y)));
          inside[h] = vandq_u64(inside[h], in);
          // bilinear(), at (0, 0) for the lanes outside.
          const float64x2_t xs =
              vreinterpretq_f64_u64(vandq_u64(vreinterpretq_u64_f64(x), inside[h]));
          const float64x2_t ys =
              vreinterpretq_f64_u64(vandq_u64(vreinterpretq_u64_f64(y), inside[h]));
          const int64x2_t xi = vcvtq_s64_f64(xs), yi = vcvtq_s64_f64(ys);
          x0[h] = vmovn_s64(xi);
          y0[h] = vmovn_s64(yi);
          fx[h] = vcvt_f32_f64(vsubq_f64(xs, vcvtq_f64_s64(xi)));
          fy[h] = vcvt_f32_f64(vsubq_f64(ys, vcvtq_f64_s64(yi)));
        }
        if (vmaxvq_u32(vreinterpretq_u32_u64(vorrq_u64(inside[0], inside[1]))) == 0) break;
        const float32x4_t fx4 = vcombine_f32(fx[0], fx[1]), fy4 = vcombine_f32(fy[0], fy[1]);
        // Each lane's two pixel pairs, two bytes at a time (little-endian:
        // the left pixel is the low byte).
        std::int32_t at[4];
        std::uint32_t upper[4], lower[4];
        vst1q_s32(at, vmlaq_s32(vcombine_s32(x0[0], x0[1]), vcombine_s32(y0[0], y0[1]), stride4));
        for (int l = 0; l < 4; ++l) {
          const std::uint8_t* r0 = frame.data + at[l];
          std::uint16_t a, b;
          std::memcpy(&a, r0, sizeof a);
          std::memcpy(&b, r0 + stride, sizeof b);
          upper[l] = a;
          lower[l] = b;
        }
        const uint32x4_t up = vld1q_u32(upper), down = vld1q_u32(lower);
        const int32x4_t a00 = vreinterpretq_s32_u32(vandq_u32(up, low_byte));
        const int32x4_t a01 = vreinterpretq_s32_u32(vshrq_n_u32(up, 8));
        const int32x4_t a10 = vreinterpretq_s32_u32(vandq_u32(down, low_byte));
        const int32x4_t a11 = vreinterpretq_s32_u32(vshrq_n_u32(down, 8));
        const float32x4_t top =
            vaddq_f32(vcvtq_f32_s32(a00), vmulq_f32(fx4, vcvtq_f32_s32(vsubq_s32(a01, a00))));
        const float32x4_t bottom =
            vaddq_f32(vcvtq_f32_s32(a10), vmulq_f32(fx4, vcvtq_f32_s32(vsubq_s32(a11, a10))));
        sum = vaddq_f32(sum, vaddq_f32(top, vmulq_f32(fy4, vsubq_f32(bottom, top))));
      }
      if (sx < q.sub) break;
    }
    float value[4];
    vst1q_f32(value, vmulq_f32(sum, vdupq_n_f32(q.weight)));
    const std::uint64_t in_lanes[4] = {vgetq_lane_u64(inside[0], 0), vgetq_lane_u64(inside[0], 1),
                                       vgetq_lane_u64(inside[1], 0), vgetq_lane_u64(inside[1], 1)};
    for (int l = 0; l < 4; ++l) {
      const std::uint32_t i = pixels[k + static_cast<std::size_t>(l)];
      const bool ok = in_lanes[l] != 0;
      valid[i] = ok ? 1 : 0;
      warped[i] = ok ? value[l] : 0.f;
    }
  }
  return k;
}
#endif

// Samples pixels[begin..end) of the level (their flags into valid, their
// values into warped). The grid is copied into locals: the byte stores to
// `valid` may alias anything reached through a pointer, which would then be
// reloaded for every pixel.
void warp_pixels(const WarpGrid& grid, ImageView frame, const std::uint32_t* pixels,
                 std::size_t begin, std::size_t end, std::uint8_t* valid, float* warped) {
#if defined(KG_DISPATCH_AVX2)
  if (simd_level() == SimdLevel::kAvx2)
    begin = warp_pixels_avx2(grid, frame, pixels, begin, end, valid, warped);
#endif
#if defined(KG_NEON_FLOAT)
  if (simd_level() != SimdLevel::kScalar)
    begin = warp_pixels_neon(grid, frame, pixels, begin, end, valid, warped);
#endif
  const WarpGrid q = grid;
  const auto w = static_cast<std::uint32_t>(q.w);
  for (std::size_t k = begin; k < end; ++k) {
    const std::uint32_t i = pixels[k];
    const double xn0 = (static_cast<int>(i % w) - q.cx) / q.half_long + q.first;
    const double yn0 = (static_cast<int>(i / w) - q.cy) / q.half_long + q.first;
    float sum = 0.f;
    bool inside = true;
    for (int sy = 0; sy < q.sub && inside; ++sy) {
      for (int sx = 0; sx < q.sub; ++sx) {
        double x, y;
        project(q.g, xn0 + sx * q.step, yn0 + sy * q.step, x, y);
        if (!(x >= 0.0 && y >= 0.0 && x < q.max_x && y < q.max_y)) {
          inside = false;
          break;
        }
        sum += bilinear(frame, x, y);
      }
    }
    valid[i] = inside ? 1 : 0;
    warped[i] = inside ? sum * q.weight : 0.f;
  }
}

// Sums of the plain correlation of appearance samples t with the warped
// frame's samples s; one place for the pose's score and the coarse level's.
struct CorrelationSums {
  double n = 0, st = 0, si = 0, stt = 0, sii = 0, sti = 0;
  void add(double t, double s) {
    n += 1;
    st += t;
    si += s;
    stt += t * t;
    sii += s * s;
    sti += t * s;
  }
  // False with fewer than min_samples samples, a flat appearance (nothing
  // to compare) or a non-finite result; a flat frame correlates 0.
  bool ncc(double min_samples, double& out) const {
    if (n < min_samples) return false;
    const double vt = stt - st * st / n, vi = sii - si * si / n;
    if (!(vt > kMinVariance * n)) return false;
    out = vi > kMinVariance * n ? (sti - st * si / n) / std::sqrt(vt * vi) : 0.0;
    return std::isfinite(out);
  }
};

}  // namespace

AppearanceAligner::AppearanceAligner(std::pmr::memory_resource* memory)
    : full_(memory),
      half_(memory),
      steepest_(memory),
      warped_(memory),
      valid_(memory),
      magnitude_(memory),
      selected_(memory),
      interior_(memory) {}

void AppearanceAligner::reserve(int max_pixels) {
  const auto n = static_cast<std::size_t>(std::max(0, max_pixels));
  // The Gauss-Newton steps use at most this many pixels (refine_level).
  const std::size_t selected = std::max(
      kMinSelected, static_cast<std::size_t>(std::ceil(kSelected * static_cast<double>(n))));
  full_.reserve(n);
  half_.reserve(n / 4 + 1);
  steepest_.reserve(selected * kParams);
  warped_.reserve(n);
  valid_.reserve(n);
  magnitude_.reserve(n);
  selected_.reserve(selected);
  interior_.reserve(n);
}

void AppearanceAligner::warp_level(const Level& level, ImageView frame, const double g[9],
                                   const std::uint32_t* pixels, std::size_t count) {
  WarpGrid grid;
  grid.w = level.width;
  grid.half_long = 0.5 * std::max(grid.w, level.height);
  grid.cx = 0.5 * (grid.w - 1);
  grid.cy = 0.5 * (level.height - 1);
  // Frame pixels per level pixel at the centre: where it exceeds one, each
  // level pixel averages a grid of samples (the appearance is area-averaged).
  const double wanted = std::ceil(footprint(level, g) - 0.25);
  // NaN or huge for a degenerate pose: one sample (which then fails the
  // bounds test) rather than a float-to-int conversion out of range.
  grid.sub = std::isfinite(wanted)
                 ? static_cast<int>(std::clamp(wanted, 1.0, static_cast<double>(kMaxSubsamples)))
                 : 1;
  grid.max_x = frame.width - 1.001;
  grid.max_y = frame.height - 1.001;
  grid.step = 1.0 / (grid.sub * grid.half_long);
  grid.first = (0.5 / grid.sub - 0.5) / grid.half_long;
  grid.weight = 1.f / static_cast<float>(grid.sub * grid.sub);
  std::copy(g, g + 9, grid.g);
  // Each pixel is sampled on its own (the listed pixels are distinct), so
  // the pixels can be split over the workers in any way.
  const int chunks = workers_ == nullptr
                         ? 1
                         : static_cast<int>(std::min<std::size_t>(
                               static_cast<std::size_t>(kChunksPerThread * workers_->threads()),
                               count / kMinChunkPixels));
  if (chunks <= 1) {
    warp_pixels(grid, frame, pixels, 0, count, valid_.data(), warped_.data());
    return;
  }
  auto chunk = [&](int c, int) {
    warp_pixels(grid, frame, pixels,
                count * static_cast<std::size_t>(c) / static_cast<std::size_t>(chunks),
                count * static_cast<std::size_t>(c + 1) / static_cast<std::size_t>(chunks),
                valid_.data(), warped_.data());
  };
  workers_->run(chunks, chunk);
}

bool AppearanceAligner::correlation(const Level& level, ImageView frame, const double g[9],
                                    double& ncc) {
  const int w = level.width, h = level.height;
  if (w < 3 || h < 3) return false;
  interior_.clear();
  for (int v = 1; v + 1 < h; ++v)
    for (int u = 1; u + 1 < w; ++u) interior_.push_back(static_cast<std::uint32_t>(v * w + u));
  if (interior_.size() < kMinScorePixels) return false;
  warp_level(level, frame, g, interior_.data(), interior_.size());
  CorrelationSums sums;
  for (const std::uint32_t i : interior_)
    if (valid_[i]) sums.add(level.values[i], warped_[i]);
  // A flat appearance cannot be compared with anything; a flat frame where
  // the model should be is no match.
  return sums.ncc(kMinInside * static_cast<double>(interior_.size()), ncc);
}

double AppearanceAligner::footprint(const Level& level, const double g[9]) {
  const double step = 1.0 / (0.5 * std::max(level.width, level.height));
  double ox, oy, ux, uy, vx, vy;
  project(g, 0.0, 0.0, ox, oy);
  project(g, step, 0.0, ux, uy);
  project(g, 0.0, step, vx, vy);
  return std::sqrt(std::fabs((ux - ox) * (vy - oy) - (uy - oy) * (vx - ox)));
}

int AppearanceAligner::refine_level(const Level& level, ImageView frame, double g[9], double* ncc,
                                    bool* ncc_measured) {
  if (ncc_measured != nullptr) *ncc_measured = false;
  const int w = level.width, h = level.height;
  const float* t = level.values;
  const double half_long = 0.5 * std::max(w, h);
  const double cx = 0.5 * (w - 1), cy = 0.5 * (h - 1);
  const auto gradient = [&](std::uint32_t i, double& gx, double& gy) {
    gx = 0.5 * (t[i + 1] - t[i - 1]) * half_long;
    gy = 0.5 * (t[i + w] - t[i - w]) * half_long;
  };

  // Only the pixels with the strongest gradients move the pose (a sign is
  // mostly flat colour): the kSelected share of the interior, ranked by
  // gradient magnitude.
  magnitude_.clear();
  for (int v = 1; v + 1 < h; ++v)
    for (int u = 1; u + 1 < w; ++u) {
      double gx, gy;
      gradient(static_cast<std::uint32_t>(v * w + u), gx, gy);
      magnitude_.push_back(static_cast<float>(gx * gx + gy * gy));
    }
  if (magnitude_.size() < 16) return 0;
  const std::size_t keep =
      std::max(std::min(kMinSelected, magnitude_.size()),
               static_cast<std::size_t>(kSelected * static_cast<double>(magnitude_.size())));
  std::nth_element(magnitude_.begin(),
                   magnitude_.begin() + static_cast<std::ptrdiff_t>(magnitude_.size() - keep),
                   magnitude_.end());
  const float threshold = std::max(magnitude_[magnitude_.size() - keep], 1e-6f);
  selected_.clear();
  for (int v = 1; v + 1 < h; ++v)
    for (int u = 1; u + 1 < w; ++u) {
      const auto i = static_cast<std::uint32_t>(v * w + u);
      double gx, gy;
      gradient(i, gx, gy);
      if (gx * gx + gy * gy >= threshold && selected_.size() < keep) selected_.push_back(i);
    }
  const std::size_t n = selected_.size();
  if (n < 16) return 0;

  // Steepest-descent images of the inverse compositional step: the
  // appearance's gradient times the warp's Jacobian at the identity.
  steepest_.resize(n * kParams);
  double t_sum = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t i = selected_[k];
    double gx, gy;
    gradient(i, gx, gy);
    const double x = (static_cast<int>(i % static_cast<std::uint32_t>(w)) - cx) / half_long;
    const double y = (static_cast<int>(i / static_cast<std::uint32_t>(w)) - cy) / half_long;
    float* sd = &steepest_[k * kParams];
    sd[0] = static_cast<float>(gx * x);
    sd[1] = static_cast<float>(gy * x);
    sd[2] = static_cast<float>(gx * y);
    sd[3] = static_cast<float>(gy * y);
    sd[4] = static_cast<float>(gx);
    sd[5] = static_cast<float>(gy);
    sd[6] = static_cast<float>(-(gx * x * x + gy * x * y));
    sd[7] = static_cast<float>(-(gx * x * y + gy * y * y));
    t_sum += t[i];
  }
  // Project gain and bias out: each steepest-descent image is made
  // orthogonal to the constant image and to the appearance itself, so a
  // brighter or lower-contrast frame moves no parameter.
  const double t_mean = t_sum / static_cast<double>(n);
  double t_norm = 0;
  for (const std::uint32_t i : selected_) t_norm += (t[i] - t_mean) * (t[i] - t_mean);
  if (!(t_norm > 1e-6)) return 0;
  t_norm = std::sqrt(t_norm);
  // Each parameter's mean and component along the appearance, then every
  // pixel's images, split over the workers (by parameter, then by pixel:
  // no two threads write one cache line), the same images for any split.
  float* steepest = steepest_.data();
  const std::uint32_t* selected = selected_.data();
  double mean[kParams], along[kParams];
  const auto moments = [&](int j) {
    double m = 0, al = 0;
    for (std::size_t k = 0; k < n; ++k) m += steepest[k * kParams + j];
    m /= static_cast<double>(n);
    for (std::size_t k = 0; k < n; ++k)
      al += (steepest[k * kParams + j] - m) * (t[selected[k]] - t_mean) / t_norm;
    mean[j] = m;
    along[j] = al;
  };
  const auto project_out = [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k)
      for (int j = 0; j < kParams; ++j)
        steepest[k * kParams + j] = static_cast<float>(
            steepest[k * kParams + j] - mean[j] - along[j] * (t[selected[k]] - t_mean) / t_norm);
  };
  const int groups =
      workers_ == nullptr || n < kMinNormalPixels ? 1 : std::min(workers_->threads(), kParams);
  if (groups <= 1) {
    for (int j = 0; j < kParams; ++j) moments(j);
    project_out(0, n);
  } else {
    auto by_parameter = [&](int c, int) {
      for (int j = c; j < kParams; j += groups) moments(j);
    };
    workers_->run(groups, by_parameter);
    const auto chunks = static_cast<std::size_t>(groups);
    auto by_pixel = [&](int c, int) {
      const auto cc = static_cast<std::size_t>(c);
      project_out(n * cc / chunks, n * (cc + 1) / chunks);
    };
    workers_->run(groups, by_pixel);
  }
  int iterations = 0;
  bool sampled = false;  // warped_ holds the selected pixels under a step's pose
  for (; iterations < kMaxIterations; ++iterations) {
    warp_level(level, frame, g, selected_.data(), n);
    sampled = true;
    double count = 0, si = 0, st = 0, sii = 0, stt = 0;
    for (const std::uint32_t i : selected_) {
      if (!valid_[i]) continue;
      count += 1;
      si += warped_[i];
      sii += static_cast<double>(warped_[i]) * warped_[i];
      st += t[i];
      stt += static_cast<double>(t[i]) * t[i];
    }
    if (count < kMinInside * static_cast<double>(n)) break;
    const double mi = si / count, mt = st / count;
    const double vi = sii / count - mi * mi, vt = stt / count - mt * mt;
    if (!(vi > kMinVariance && vt > kMinVariance)) break;
    const double gain = std::sqrt(vt / vi);
    // Robust scale of the residuals (median absolute value): occluders,
    // glare and the background at the model's border give residuals far
    // beyond it, which Tukey's weights then ignore.
    magnitude_.clear();
    for (const std::uint32_t i : selected_) {
      if (!valid_[i]) continue;
      magnitude_.push_back(static_cast<float>(std::fabs(gain * (warped_[i] - mi) - (t[i] - mt))));
    }
    const auto middle = magnitude_.begin() + static_cast<std::ptrdiff_t>(magnitude_.size() / 2);
    std::nth_element(magnitude_.begin(), middle, magnitude_.end());
    const double sigma = std::max(1.4826 * static_cast<double>(*middle), kMinResidualScale);
    const double cutoff = kTukey * sigma;
    double b[kParams] = {};
    double a[kParams][kParams] = {};
    const NormalTerms terms{selected_.data(),
                            n,
                            valid_.data(),
                            warped_.data(),
                            t,
                            steepest_.data(),
                            gain,
                            mi,
                            mt,
                            cutoff};
    normal_equations(terms, workers_, a, b);
    for (int j = 0; j < kParams; ++j)
      for (int l = j + 1; l < kParams; ++l) a[j][l] = a[l][j];
    double dp[kParams];
    if (!solve8(a, b, dp)) break;
    const double step[9] = {1.0 + dp[0], dp[2], dp[4], dp[1], 1.0 + dp[3],
                            dp[5],       dp[6], dp[7], 1.0};
    double inverse[9];
    if (!invert(step, inverse)) break;
    multiply(g, inverse, g);
    // Stop when the step moves no corner of the level by more than
    // kConverged of its pixels.
    double largest = 0;
    for (const double sx : {-1.0, 1.0})
      for (const double sy : {-1.0, 1.0}) {
        const double x = sx * cx / half_long, y = sy * cy / half_long;
        const double z = step[6] * x + step[7] * y + step[8];
        const double dx = (step[0] * x + step[1] * y + step[2]) / z - x;
        const double dy = (step[3] * x + step[4] * y + step[5]) / z - y;
        largest = std::max(largest, std::hypot(dx, dy) * half_long);
      }
    if (!std::isfinite(largest)) break;
    if (largest < kConverged) {
      ++iterations;
      break;
    }
  }
  if (ncc != nullptr && ncc_measured != nullptr && sampled) {
    // The last step's samples (before its update: under kConverged of a
    // level pixel away once converged), plain correlation.
    CorrelationSums sums;
    for (const std::uint32_t i : selected_)
      if (valid_[i]) sums.add(t[i], warped_[i]);
    *ncc_measured = sums.ncc(kMinInside * static_cast<double>(n), *ncc);
  }
  return iterations;
}

bool AppearanceAligner::prepare(const AppearanceImage& appearance, ImageView frame) {
  const int w = appearance.width, hgt = appearance.height;
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(hgt);
  if (appearance.pixels == nullptr || w < 3 || hgt < 3 || !(appearance.scale_x > 0.f) ||
      !(appearance.scale_y > 0.f) || n > full_.capacity() || frame.width < 2 || frame.height < 2)
    return false;
  // The appearance lightly smoothed ([1 2 1] / 4 each way), matching the
  // blur of the frame it is compared with.
  full_.resize(n);
  warped_.resize(n);
  valid_.resize(n);
  for (int v = 0; v < hgt; ++v) {
    const std::uint8_t* r = appearance.pixels + static_cast<std::size_t>(v) * w;
    for (int u = 0; u < w; ++u) {
      const int l = std::max(u - 1, 0), rr = std::min(u + 1, w - 1);
      warped_[static_cast<std::size_t>(v) * w + u] = 0.25f * (r[l] + 2.f * r[u] + r[rr]);
    }
  }
  for (int v = 0; v < hgt; ++v) {
    const int up = std::max(v - 1, 0), down = std::min(v + 1, hgt - 1);
    for (int u = 0; u < w; ++u)
      full_[static_cast<std::size_t>(v) * w + u] =
          0.25f * (warped_[static_cast<std::size_t>(up) * w + u] +
                   2.f * warped_[static_cast<std::size_t>(v) * w + u] +
                   warped_[static_cast<std::size_t>(down) * w + u]);
  }
  return true;
}

AppearanceFit AppearanceAligner::align(const AppearanceImage& appearance, ImageView frame,
                                       Homography& h, double abandon_below, double refuse_below) {
  AppearanceFit fit;
  if (!prepare(appearance, frame)) return fit;
  const int w = appearance.width, hgt = appearance.height;
  const Level full{full_.data(), w, hgt, appearance.scale_x, appearance.scale_y};
  Level half{};
  if (std::max(w, hgt) / 2 >= kMinHalfLongEdge && std::min(w, hgt) / 2 >= kMinHalfLongEdge / 2) {
    half.width = w / 2;
    half.height = hgt / 2;
    half.scale_x = appearance.scale_x * 0.5f;
    half.scale_y = appearance.scale_y * 0.5f;
    half_.resize(static_cast<std::size_t>(half.width) * half.height);
    for (int v = 0; v < half.height; ++v)
      for (int u = 0; u < half.width; ++u) {
        const float* r0 = &full_[static_cast<std::size_t>(2 * v) * w + 2 * u];
        half_[static_cast<std::size_t>(v) * half.width + u] =
            0.25f * (r0[0] + r0[1] + r0[w] + r0[w + 1]);
      }
    half.values = half_.data();
  }

  double to_model[9], from_model[9], g[9];
  level_to_model(w, hgt, full.scale_x, full.scale_y, to_model);
  if (!invert(to_model, from_model)) return fit;
  multiply(h.data(), to_model, g);
  double half_to_model[9] = {}, half_from_model[9] = {};
  if (half.values != nullptr) {
    level_to_model(half.width, half.height, half.scale_x, half.scale_y, half_to_model);
    if (!invert(half_to_model, half_from_model)) half.values = nullptr;
  }
  // The correlation is scored on the level closest to the frame's
  // resolution: a sign smaller in the frame than its appearance would
  // otherwise be marked down for the detail the frame cannot show.
  const bool score_half = half.values != nullptr && footprint(full, g) < kScoreOnHalfBelow;
  const Level& score_level = score_half ? half : full;
  const auto score = [&](const double* hom, double& ncc) {
    double gs[9];
    multiply(hom, score_half ? half_to_model : to_model, gs);
    return correlation(score_level, frame, gs, ncc);
  };
  fit.measured = score(h.data(), fit.ncc_before);
  if (!fit.measured) return fit;
  fit.ncc = fit.ncc_before;
  if (fit.ncc_before < refuse_below) {
    fit.abandoned = true;  // not worth a step
    return fit;
  }

  double refined[9];
  std::copy(h.begin(), h.end(), refined);
  if (half.values != nullptr) {
    multiply(refined, half_to_model, g);
    fit.iterations += refine_level(half, frame, g, &fit.ncc_coarse, &fit.coarse_measured);
    if (fit.coarse_measured && fit.ncc_coarse < abandon_below && fit.ncc_before < abandon_below) {
      // Neither the pose given nor the coarse level's fit correlates well
      // enough: the fine level (four times the pixels) is not run.
      fit.abandoned = true;
      return fit;
    }
    multiply(g, half_from_model, refined);
  }
  multiply(refined, to_model, g);
  fit.iterations += refine_level(full, frame, g);
  multiply(g, from_model, refined);
  if (!(std::fabs(refined[8]) > 1e-12)) return fit;
  for (double& v : refined) v /= refined[8];
  double ncc = -1.0;
  if (!score(refined, ncc) || !(ncc > fit.ncc_before)) return fit;
  for (int i = 0; i < 9; ++i) h[static_cast<std::size_t>(i)] = refined[i];
  fit.aligned = true;
  fit.ncc = ncc;
  return fit;
}

}  // namespace kg
