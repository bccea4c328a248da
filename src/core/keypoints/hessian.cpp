#include "core/keypoints/hessian.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "core/image/blur.h"
#include "core/support/simd_dispatch.h"
#include "core/support/strongest.h"

#if defined(KG_NEON_FLOAT)
#include <arm_neon.h>
#endif
#if defined(KG_DISPATCH_AVX2)
#include <immintrin.h>
#endif

namespace kg {
namespace {

constexpr float kSigma0 = 1.6f;                  // first level of each octave (Lowe's SIFT value)
constexpr float kInputSigma = 0.5f;              // blur a camera image already has
constexpr int kBorder = 2;                       // det(H) reads 1 px around, the 3x3x3 test 1 more
constexpr double kMaxOffset = 0.6;               // larger refinement offsets: not a stable extremum
constexpr double kHalvingVariance = 1.0 / 16.0;  // 2x2 box, in the halved image's pixels

// Strongest first; ties by position so the order never depends on the scan.
bool stronger(const Keypoint& a, const Keypoint& b) {
  if (a.response != b.response) return a.response > b.response;
  if (a.y != b.y) return a.y < b.y;
  if (a.x != b.x) return a.x < b.x;
  return a.scale < b.scale;
}

// With kNeon the loops below have NEON versions (AArch64): the same
// operations in the same order on 4 pixels at a time, so the same values.
template <bool kNeon>
KG_ALWAYS_INLINE void to_unit_float(ImageView image, Plane<float>& dst, int y0, int y1) {
  constexpr float kScale = 1.f / 255.f;
  for (int y = y0; y < y1; ++y) {
    const std::uint8_t* s = image.row(y);
    float* d = dst.row(y);
    int x = 0;
#if defined(KG_NEON_FLOAT)
    if constexpr (kNeon) {
      for (; x + 8 <= image.width; x += 8) {
        const uint16x8_t wide = vmovl_u8(vld1_u8(s + x));
        vst1q_f32(d + x, vmulq_n_f32(vcvtq_f32_u32(vmovl_u16(vget_low_u16(wide))), kScale));
        vst1q_f32(d + x + 4, vmulq_n_f32(vcvtq_f32_u32(vmovl_u16(vget_high_u16(wide))), kScale));
      }
    }
#endif
    for (; x < image.width; ++x) d[x] = kScale * static_cast<float>(s[x]);
  }
}

// Pixel x of row m1 (rows m0, m2 around it) is above the threshold and
// its 8 neighbours in the level: strictly above those before it in scan
// order, at least equal to those after. Branch-free so it vectorises.
KG_ALWAYS_INLINE bool level_maximum(const float* m0, const float* m1, const float* m2, int x,
                                    float thr) {
  const float v = m1[x];
  return (v > thr) & (v > m1[x - 1]) & (v >= m1[x + 1]) & (v > m0[x - 1]) & (v > m0[x]) &
         (v > m0[x + 1]) & (v >= m2[x - 1]) & (v >= m2[x]) & (v >= m2[x + 1]);
}

// Appends (x, y) to `cand` when pixel x of row m1 is above its 9
// neighbours in the level below (rows l0, l1, l2); false when that would
// pass `limit` ints (nothing appended then).
KG_ALWAYS_INLINE bool offer_candidate(const float* m1, const float* l0, const float* l1,
                                      const float* l2, int x, int y, WorkVector<std::int32_t>& cand,
                                      std::size_t limit) {
  const float v = m1[x];
  const bool below = (v > l0[x - 1]) & (v > l0[x]) & (v > l0[x + 1]) & (v > l1[x - 1]) &
                     (v > l1[x]) & (v > l1[x + 1]) & (v > l2[x - 1]) & (v > l2[x]) &
                     (v > l2[x + 1]);
  if (!below) return true;
  if (cand.size() + 2 > limit) return false;
  cand.push_back(x);
  cand.push_back(y);
  return true;
}

// Appends (x, y) of the pixels of row y (rows m0, m1, m2 around it) that
// are above the threshold, above their 8 neighbours in the level and, with
// the level below (rows l0, l1, l2 of its response), above the 9 there:
// all of the 3x3x3 test but the level above, which is not computed yet.
// It runs while the rows are in cache: done later per candidate, these
// reads missed the cache and the comparisons mispredicted, for the tens of
// thousands of candidates of a frame that fail them. The level test is
// branch-free so the compiler vectorises it; the few pixels that pass it
// take the level-below test one by one. Candidates beyond `limit` ints are
// dropped; returns false then.
template <bool kNeon>
KG_ALWAYS_INLINE bool collect_candidates(const float* m0, const float* m1, const float* m2,
                                         const float* l0, const float* l1, const float* l2, int y,
                                         int w, float thr, std::uint8_t* mask,
                                         WorkVector<std::int32_t>& cand, std::size_t limit) {
  int x = kBorder;
#if defined(KG_NEON_FLOAT)
  if constexpr (kNeon) {
    const float32x4_t t = vdupq_n_f32(thr);
    const auto level4 = [&](int at) {
      const float32x4_t v = vld1q_f32(m1 + at);
      uint32x4_t m = vandq_u32(vcgtq_f32(v, t), vcgtq_f32(v, vld1q_f32(m1 + at - 1)));
      m = vandq_u32(m, vcgeq_f32(v, vld1q_f32(m1 + at + 1)));
      m = vandq_u32(
          m, vandq_u32(vcgtq_f32(v, vld1q_f32(m0 + at - 1)), vcgtq_f32(v, vld1q_f32(m0 + at))));
      m = vandq_u32(
          m, vandq_u32(vcgtq_f32(v, vld1q_f32(m0 + at + 1)), vcgeq_f32(v, vld1q_f32(m2 + at - 1))));
      m = vandq_u32(
          m, vandq_u32(vcgeq_f32(v, vld1q_f32(m2 + at)), vcgeq_f32(v, vld1q_f32(m2 + at + 1))));
      return vmovn_u32(m);
    };
    for (; x + 8 <= w - kBorder; x += 8) {
      // Most pixels are under the threshold: 8 of them clear at once.
      const uint32x4_t over =
          vorrq_u32(vcgtq_f32(vld1q_f32(m1 + x), t), vcgtq_f32(vld1q_f32(m1 + x + 4), t));
      if (vmaxvq_u32(over) == 0) {
        vst1_u8(mask + x, vdup_n_u8(0));
        continue;
      }
      const uint8x8_t flags = vmovn_u16(vcombine_u16(level4(x), level4(x + 4)));
      vst1_u8(mask + x, vand_u8(flags, vdup_n_u8(1)));
    }
  }
#endif
  for (; x < w - kBorder; ++x)
    mask[x] = static_cast<std::uint8_t>(level_maximum(m0, m1, m2, x, thr));
  std::fill(mask + std::max(w - kBorder, 0), mask + w + 8, std::uint8_t{0});
  for (x = kBorder; x < w - kBorder; ++x) {
    if ((x & 7) == 0) {  // skip 8 empty bytes at once
      std::uint64_t eight;
      std::memcpy(&eight, mask + x, sizeof eight);
      if (eight == 0) {
        x += 7;
        continue;
      }
    }
    if (mask[x] && !offer_candidate(m1, l0, l1, l2, x, y, cand, limit)) return false;
  }
  return true;
}

#if defined(KG_DISPATCH_AVX2)
// v > p[0..7], v >= p[0..7]: masks for collect_candidates_avx2 (helpers,
// not lambdas: those would not be compiled for AVX2).
KG_TARGET_AVX2 KG_ALWAYS_INLINE __m256 gt8(__m256 v, const float* p) {
  return _mm256_cmp_ps(v, _mm256_loadu_ps(p), _CMP_GT_OQ);
}
KG_TARGET_AVX2 KG_ALWAYS_INLINE __m256 ge8(__m256 v, const float* p) {
  return _mm256_cmp_ps(v, _mm256_loadu_ps(p), _CMP_GE_OQ);
}

// collect_candidates' values with AVX2 intrinsics: the level test 8 pixels
// at a time, skipping the pixels under the threshold (most of them) after
// one comparison, and its bits read straight from the comparison mask, so
// no mask row is written and scanned. The same candidates in the same order.
KG_TARGET_AVX2 inline bool collect_candidates_avx2(const float* m0, const float* m1,
                                                   const float* m2, const float* l0,
                                                   const float* l1, const float* l2, int y, int w,
                                                   float thr, WorkVector<std::int32_t>& cand,
                                                   std::size_t limit) {
  const __m256 t = _mm256_set1_ps(thr);
  int x = kBorder;
  for (; x + 8 <= w - kBorder; x += 8) {
    const __m256 v = _mm256_loadu_ps(m1 + x);
    const __m256 over = _mm256_cmp_ps(v, t, _CMP_GT_OQ);
    if (_mm256_testz_ps(over, over)) continue;
    __m256 m = _mm256_and_ps(over, _mm256_and_ps(gt8(v, m1 + x - 1), ge8(v, m1 + x + 1)));
    m = _mm256_and_ps(m, _mm256_and_ps(gt8(v, m0 + x - 1), gt8(v, m0 + x)));
    m = _mm256_and_ps(m, _mm256_and_ps(gt8(v, m0 + x + 1), ge8(v, m2 + x - 1)));
    m = _mm256_and_ps(m, _mm256_and_ps(ge8(v, m2 + x), ge8(v, m2 + x + 1)));
    for (auto bits = static_cast<unsigned>(_mm256_movemask_ps(m)); bits != 0; bits &= bits - 1)
      if (!offer_candidate(m1, l0, l1, l2, x + __builtin_ctz(bits), y, cand, limit)) return false;
  }
  for (; x < w - kBorder; ++x)
    if (level_maximum(m0, m1, m2, x, thr) && !offer_candidate(m1, l0, l1, l2, x, y, cand, limit))
      return false;
  return true;
}
#endif

// Scale-normalised sigma^4 (Lxx Lyy - Lxy^2) of row y by central
// differences, for every pixel with both horizontal neighbours.
template <bool kNeon>
KG_ALWAYS_INLINE void response_row(const Plane<float>& L, int y, float norm, float* r) {
  const int w = L.width();
  const float* a = L.row(y - 1);
  const float* b = L.row(y);
  const float* c = L.row(y + 1);
  int x = 1;
#if defined(KG_NEON_FLOAT)
  if constexpr (kNeon) {
    for (; x + 4 <= w - 1; x += 4) {
      const float32x4_t bc = vld1q_f32(b + x);
      const float32x4_t twice = vmulq_n_f32(bc, 2.f);
      const float32x4_t dxx =
          vsubq_f32(vaddq_f32(vld1q_f32(b + x - 1), vld1q_f32(b + x + 1)), twice);
      const float32x4_t dyy = vsubq_f32(vaddq_f32(vld1q_f32(a + x), vld1q_f32(c + x)), twice);
      const float32x4_t dxy =
          vmulq_n_f32(vsubq_f32(vsubq_f32(vld1q_f32(c + x + 1), vld1q_f32(c + x - 1)),
                                vsubq_f32(vld1q_f32(a + x + 1), vld1q_f32(a + x - 1))),
                      0.25f);
      vst1q_f32(r + x, vmulq_n_f32(vsubq_f32(vmulq_f32(dxx, dyy), vmulq_f32(dxy, dxy)), norm));
    }
  }
#endif
  for (; x < w - 1; ++x) {
    const float dxx = (b[x - 1] + b[x + 1]) - 2.f * b[x];
    const float dyy = (a[x] + c[x]) - 2.f * b[x];
    const float dxy = 0.25f * ((c[x + 1] - c[x - 1]) - (a[x + 1] - a[x - 1]));
    r[x] = norm * (dxx * dyy - dxy * dxy);
  }
}

// The response rows of [y0, y1) that have all 8 neighbours (the 1-px frame
// is never written). With `cand`, also the extremum candidates of those
// rows, collected while the rows are still in cache; `below` is then the
// response of the level below. With `halo` (bands but the only one), two
// rows for the responses of rows y0 - 1 and y1, which the candidate test
// and the scan of the level below read and the neighbouring bands write.
// kAvx2: the candidates by collect_candidates_avx2 (x86-64 only).
template <bool kNeon, bool kAvx2 = false>
KG_ALWAYS_INLINE bool hessian_band_rows(const Plane<float>& L, float norm, float threshold,
                                        Plane<float>& R, int y0, int y1, const Plane<float>* below,
                                        std::uint8_t* mask, float* halo,
                                        WorkVector<std::int32_t>* cand, std::size_t limit) {
  const int w = L.width();
  const int h = L.height();
  const int r0 = std::max(y0, 1);
  const int r1 = std::min(y1, h - 1);
  // Candidate rows.
  const int c0 = std::max(y0, kBorder);
  const int c1 = std::min(y1, h - kBorder);
  const bool collect = cand != nullptr && c0 < c1;
  const bool halos = halo != nullptr && c0 < c1;
  float* above = halo;
  float* after = halo != nullptr ? halo + w : nullptr;
  const auto response = [&](int y) -> const float* {
    return y < y0 ? above : y >= y1 ? after : R.row(y);
  };
  // The candidates of row c, with the response rows around it.
  const auto candidates = [&](const float* m0, const float* m1, const float* m2, int c) {
#if defined(KG_DISPATCH_AVX2)
    if constexpr (kAvx2)
      return collect_candidates_avx2(m0, m1, m2, below->row(c - 1), below->row(c),
                                     below->row(c + 1), c, w, threshold, *cand, limit);
#endif
    return collect_candidates<kNeon>(m0, m1, m2, below->row(c - 1), below->row(c),
                                     below->row(c + 1), c, w, threshold, mask, *cand, limit);
  };
  if (halos && c0 - 1 < y0) response_row<kNeon>(L, c0 - 1, norm, above);
  bool complete = true;
  for (int y = r0; y < r1; ++y) {
    response_row<kNeon>(L, y, norm, R.row(y));
    // Row y - 1 has both response neighbours now.
    const int c = y - 1;
    if (collect && complete && c >= c0 && c < c1)
      complete = candidates(response(c - 1), R.row(c), R.row(y), c);
  }
  // The band's last candidate row, when its row below is the next band's.
  if (halos && c1 >= r1) {
    response_row<kNeon>(L, c1, norm, after);
    if (collect && complete)
      complete = candidates(response(c1 - 2), response(c1 - 1), after, c1 - 1);
  }
  return complete;
}

// hessian_band_rows for the baseline and (x86-64) AVX2; see
// core/support/simd_dispatch.h.
bool hessian_band_baseline(const Plane<float>& L, float norm, float threshold, Plane<float>& R,
                           int y0, int y1, const Plane<float>* below, std::uint8_t* mask,
                           float* halo, WorkVector<std::int32_t>* cand, std::size_t limit) {
  return hessian_band_rows<false>(L, norm, threshold, R, y0, y1, below, mask, halo, cand, limit);
}
#if defined(KG_DISPATCH_AVX2)
KG_TARGET_AVX2 bool hessian_band_avx2(const Plane<float>& L, float norm, float threshold,
                                      Plane<float>& R, int y0, int y1, const Plane<float>* below,
                                      std::uint8_t* mask, float* halo,
                                      WorkVector<std::int32_t>* cand, std::size_t limit) {
  return hessian_band_rows<false, true>(L, norm, threshold, R, y0, y1, below, mask, halo, cand,
                                        limit);
}
#endif
#if defined(KG_NEON_FLOAT)
bool hessian_band_neon(const Plane<float>& L, float norm, float threshold, Plane<float>& R, int y0,
                       int y1, const Plane<float>* below, std::uint8_t* mask, float* halo,
                       WorkVector<std::int32_t>* cand, std::size_t limit) {
  return hessian_band_rows<true>(L, norm, threshold, R, y0, y1, below, mask, halo, cand, limit);
}
#endif

bool hessian_band(const Plane<float>& L, float norm, float threshold, Plane<float>& R, int y0,
                  int y1, const Plane<float>* below, std::uint8_t* mask, float* halo,
                  WorkVector<std::int32_t>* cand, std::size_t limit) {
#if defined(KG_DISPATCH_AVX2)
  if (simd_level() == SimdLevel::kAvx2)
    return hessian_band_avx2(L, norm, threshold, R, y0, y1, below, mask, halo, cand, limit);
#elif defined(KG_NEON_FLOAT)
  if (simd_level() != SimdLevel::kScalar)
    return hessian_band_neon(L, norm, threshold, R, y0, y1, below, mask, halo, cand, limit);
#endif
  return hessian_band_baseline(L, norm, threshold, R, y0, y1, below, mask, halo, cand, limit);
}

// Halves the image by averaging 2x2 blocks (a trailing odd row or column is
// dropped). Output pixel x covers input pixels 2x and 2x + 1, so its centre
// is input 2x + 0.5: the half-pixel shift is undone when keypoints are mapped
// back. Averaging (unlike taking every other pixel) commutes with 90-degree
// rotations of even-sized images, and adds a variance of 1/16 in output
// pixels, which the caller accounts for. The source level has twice the
// octave's first sigma, so this does not alias.
template <bool kNeon>
KG_ALWAYS_INLINE void halve_rows(const Plane<float>& src, Plane<float>& dst, int y0, int y1) {
  const int w = dst.width();
  for (int y = y0; y < y1; ++y) {
    const float* a = src.row(2 * y);
    const float* b = src.row(2 * y + 1);
    float* d = dst.row(y);
    int x = 0;
#if defined(KG_NEON_FLOAT)
    if constexpr (kNeon) {
      for (; x + 4 <= w; x += 4) {
        const float32x4x2_t p = vld2q_f32(a + 2 * x);  // even and odd pixels
        const float32x4x2_t q = vld2q_f32(b + 2 * x);
        vst1q_f32(d + x, vmulq_n_f32(vaddq_f32(vaddq_f32(p.val[0], p.val[1]),
                                               vaddq_f32(q.val[0], q.val[1])),
                                     0.25f));
      }
    }
#endif
    for (; x < w; ++x) d[x] = 0.25f * ((a[2 * x] + a[2 * x + 1]) + (b[2 * x] + b[2 * x + 1]));
  }
}

// to_unit_float and halve_rows at the best level: the portable loops for
// the baseline and (x86-64) AVX2, or the NEON ones.
void to_unit_float_baseline(ImageView image, Plane<float>& dst, int y0, int y1) {
  to_unit_float<false>(image, dst, y0, y1);
}
void halve_rows_baseline(const Plane<float>& src, Plane<float>& dst, int y0, int y1) {
  halve_rows<false>(src, dst, y0, y1);
}
#if defined(KG_DISPATCH_AVX2)
KG_TARGET_AVX2 void to_unit_float_avx2(ImageView image, Plane<float>& dst, int y0, int y1) {
  to_unit_float<false>(image, dst, y0, y1);
}
KG_TARGET_AVX2 void halve_rows_avx2(const Plane<float>& src, Plane<float>& dst, int y0, int y1) {
  halve_rows<false>(src, dst, y0, y1);
}
#endif
void to_unit_float_rows(ImageView image, Plane<float>& dst, int y0, int y1) {
#if defined(KG_DISPATCH_AVX2)
  if (simd_level() == SimdLevel::kAvx2) return to_unit_float_avx2(image, dst, y0, y1);
#elif defined(KG_NEON_FLOAT)
  if (simd_level() != SimdLevel::kScalar) return to_unit_float<true>(image, dst, y0, y1);
#endif
  to_unit_float_baseline(image, dst, y0, y1);
}
void halve(const Plane<float>& src, Plane<float>& dst, int y0, int y1) {
#if defined(KG_DISPATCH_AVX2)
  if (simd_level() == SimdLevel::kAvx2) return halve_rows_avx2(src, dst, y0, y1);
#elif defined(KG_NEON_FLOAT)
  if (simd_level() != SimdLevel::kScalar) return halve_rows<true>(src, dst, y0, y1);
#endif
  halve_rows_baseline(src, dst, y0, y1);
}

// Band `band` of `bands` over `rows` rows: [begin, end).
struct Rows {
  int begin;
  int end;
};
Rows band_rows(int rows, int band, int bands) {
  return {static_cast<int>(static_cast<long long>(rows) * band / bands),
          static_cast<int>(static_cast<long long>(rows) * (band + 1) / bands)};
}

// Levels smaller than this many pixels per band run on fewer bands: waking
// the workers would cost more than the work. (A 640x480 frame's third
// octave, 160x120, runs on two bands: it was 2 M instructions a frame on
// the caller alone; the workers poll for the next run, WorkerPool.)
constexpr long long kMinBandPixels = 8192;

// Solves H o = -g (H symmetric 3x3) by Cramer's rule; false when singular.
bool solve_offset(const double H[3][3], const double g[3], double o[3]) {
  const double c00 = H[1][1] * H[2][2] - H[1][2] * H[2][1];
  const double c01 = H[1][2] * H[2][0] - H[1][0] * H[2][2];
  const double c02 = H[1][0] * H[2][1] - H[1][1] * H[2][0];
  const double det = H[0][0] * c00 + H[0][1] * c01 + H[0][2] * c02;
  if (!(std::fabs(det) > 0.0)) return false;
  const double inv[3][3] = {
      {c00, H[0][2] * H[2][1] - H[0][1] * H[2][2], H[0][1] * H[1][2] - H[0][2] * H[1][1]},
      {c01, H[0][0] * H[2][2] - H[0][2] * H[2][0], H[0][2] * H[1][0] - H[0][0] * H[1][2]},
      {c02, H[0][1] * H[2][0] - H[0][0] * H[2][1], H[0][0] * H[1][1] - H[0][1] * H[1][0]}};
  for (int i = 0; i < 3; ++i)
    o[i] = -(inv[i][0] * g[0] + inv[i][1] * g[1] + inv[i][2] * g[2]) / det;
  return std::isfinite(o[0]) && std::isfinite(o[1]) && std::isfinite(o[2]);
}

struct LevelInfo {
  int level;           // scale index inside the octave
  float octave_scale;  // 2^octave: octave pixels to input pixels
  float threshold;
  float sigma0;
  float log_k;  // log of the scale ratio between levels
};

// The response of the level above as one band's scan reads it while the
// level above is computed: the band's rows [y0, y1) in `plane`, rows y0 - 1
// and y1 (the neighbouring bands') from the band's halo.
struct BandRows {
  const Plane<float>* plane;
  int y0;
  int y1;
  const float* above;
  const float* after;
  const float* row(int y) const { return y < y0 ? above : y >= y1 ? after : plane->row(y); }
};

// Local maxima of `mid` over its 26 neighbours in (lo, mid, hi), among the
// `ints` / 2 candidates collected with it (already above their 17
// neighbours in lo and mid, so only hi is left to test); refined and
// offered to the heap `out`. A plateau yields one maximum: values must be
// strictly above the neighbours before them in (scale, y, x) order, and at
// least equal to those after.
void scan_level(const std::int32_t* cand, std::size_t ints, const Plane<float>& lo,
                const Plane<float>& mid, const BandRows& hi, const LevelInfo& info,
                int max_keypoints, WorkVector<Keypoint>& out) {
  for (std::size_t i = 0; i + 1 < ints; i += 2) {
    const int x = cand[i];
    const int y = cand[i + 1];
    const float* m0 = mid.row(y - 1);
    const float* m1 = mid.row(y);
    const float* m2 = mid.row(y + 1);
    const float v = m1[x];
    const float* l0 = lo.row(y - 1);
    const float* l1 = lo.row(y);
    const float* l2 = lo.row(y + 1);
    const float* h0 = hi.row(y - 1);
    const float* h1 = hi.row(y);
    const float* h2 = hi.row(y + 1);
    // The level and the level below were tested when collecting.
    bool is_max = true;
    for (int dx = -1; dx <= 1 && is_max; ++dx)
      is_max = v >= h0[x + dx] && v >= h1[x + dx] && v >= h2[x + dx];
    if (!is_max) continue;

    // Quadratic fit in (x, y, scale) from central differences.
    const double c = v;
    const double g[3] = {0.5 * (static_cast<double>(m1[x + 1]) - m1[x - 1]),
                         0.5 * (static_cast<double>(m2[x]) - m0[x]),
                         0.5 * (static_cast<double>(h1[x]) - l1[x])};
    const double dxx = static_cast<double>(m1[x + 1]) + m1[x - 1] - 2.0 * c;
    const double dyy = static_cast<double>(m2[x]) + m0[x] - 2.0 * c;
    const double dss = static_cast<double>(h1[x]) + l1[x] - 2.0 * c;
    const double dxy = 0.25 * ((static_cast<double>(m2[x + 1]) - m2[x - 1]) -
                               (static_cast<double>(m0[x + 1]) - m0[x - 1]));
    const double dxs = 0.25 * ((static_cast<double>(h1[x + 1]) - h1[x - 1]) -
                               (static_cast<double>(l1[x + 1]) - l1[x - 1]));
    const double dys =
        0.25 * ((static_cast<double>(h2[x]) - h0[x]) - (static_cast<double>(l2[x]) - l0[x]));
    const double H[3][3] = {{dxx, dxy, dxs}, {dxy, dyy, dys}, {dxs, dys, dss}};
    double o[3];
    if (!solve_offset(H, g, o)) continue;
    if (std::fabs(o[0]) > kMaxOffset || std::fabs(o[1]) > kMaxOffset ||
        std::fabs(o[2]) > kMaxOffset)
      continue;
    Keypoint kp;
    // Octave pixel x has its centre at input (x + 0.5) 2^octave - 0.5 (see halve()).
    kp.x = static_cast<float>((x + o[0] + 0.5) * info.octave_scale - 0.5);
    kp.y = static_cast<float>((y + o[1] + 0.5) * info.octave_scale - 0.5);
    kp.scale = static_cast<float>(info.sigma0 * std::exp((info.level + o[2]) * info.log_k) *
                                  info.octave_scale);
    kp.response = static_cast<float>(c + 0.5 * (g[0] * o[0] + g[1] * o[1] + g[2] * o[2]));
    // Bounded memory however many extrema there are.
    offer_strongest(out, kp, static_cast<std::size_t>(std::max(0, max_keypoints)), stronger);
  }
}

}  // namespace

// One scale level's work, done band by band: the response of `L` into `R`
// (with the level below `below` and the candidates into each band's list
// `collect`, when set), the scan of the level below's candidates (`scan`:
// the bands' lists of the run before, with the same bands; levels
// `scan_lo` and `scan_mid`, and `R` above them) into each band's heap, the
// blur of `L` into `blurred`, the halving of `L` into `halved` and, for the
// input, its conversion to float in `unit`.
struct HessianDetector::Level {
  ImageView image;
  Plane<float>* unit = nullptr;
  const Plane<float>* L = nullptr;
  float norm = 0.f;
  float threshold = 0.f;
  Plane<float>* R = nullptr;
  const Plane<float>* below = nullptr;
  int collect = -1;  // the bands' candidate list (slot) to fill
  int scan = -1;     // the bands' candidate list to scan
  const Plane<float>* scan_lo = nullptr;
  const Plane<float>* scan_mid = nullptr;
  LevelInfo scan_info{};
  int max_keypoints = 0;
  WorkVector<Keypoint>* strongest = nullptr;  // the first band's heap
  float blur_sigma = 0.f;
  Plane<float>* blurred = nullptr;
  Plane<float>* halved = nullptr;
};

HessianDetector::HessianDetector(std::pmr::memory_resource* memory)
    : levels_{Plane<float>(memory), Plane<float>(memory)},
      responses_{Plane<float>(memory), Plane<float>(memory), Plane<float>(memory)},
      next_octave_(memory),
      bands_{Band(memory), Band(memory), Band(memory), Band(memory),
             Band(memory), Band(memory), Band(memory), Band(memory)},
      copy_(memory) {}

void HessianDetector::reserve(int max_width, int max_height, const KeypointParams& params,
                              int max_keypoints, int max_candidates, int threads) {
  for (Plane<float>& p : levels_) p.reserve(max_width, max_height);
  for (Plane<float>& p : responses_) p.reserve(max_width, max_height);
  next_octave_.reserve(max_width / 2, max_height / 2);
  // The widest blur is below the top level's total sigma.
  const int levels = std::max(1, params.hessian_levels);
  const int radius = blur_radius(
      static_cast<float>(kSigma0 * std::pow(2.0, static_cast<double>(levels + 1) / levels)));
  max_candidate_ints_ = 2 * static_cast<std::size_t>(std::max(0, max_candidates));
  const auto keep = static_cast<std::size_t>(std::max(0, max_keypoints));
  reserved_bands_ = std::clamp(threads, 1, kMaxBands);
  for (int b = 0; b < reserved_bands_; ++b) {
    Band& band = bands_[static_cast<std::size_t>(b)];
    band.scratch.reserve(max_width + 2 * radius, 1);
    band.mask.reserve(static_cast<std::size_t>(max_width) + 8);
    if (reserved_bands_ > 1) band.halo.reserve(max_width, 2);
    for (auto& c : band.candidates) c.reserve(max_candidate_ints_);
    // The first band's maxima go straight into detect()'s output.
    if (b > 0) band.strongest.reserve(keep);
  }
  copy_.reserve(static_cast<std::size_t>(std::max(0, max_keypoints)));
}

void HessianDetector::detect(ImageView image, const KeypointParams& params, int max_keypoints,
                             std::vector<Keypoint>& out) {
  detect(image, params, max_keypoints, copy_);
  out.assign(copy_.begin(), copy_.end());
}

int HessianDetector::bands_for(int w, int h) const {
  if (workers_ == nullptr) return 1;
  const long long most = std::min(workers_->threads(), reserved_bands_);
  return static_cast<int>(std::clamp(static_cast<long long>(w) * h / kMinBandPixels, 1LL,
                                     std::min<long long>(most, h)));
}

void HessianDetector::run_level(const Level& level, int bands) {
  const Plane<float>& L = level.L ? *level.L : *level.unit;
  const int w = L.width();
  const int h = L.height();
  if (level.R) level.R->resize(w, h);
  if (level.blurred) level.blurred->resize(w, h);
  if (level.halved) level.halved->resize(w / 2, h / 2);
  auto task = [&](int b, int /*worker*/) {
    Band& band = bands_[static_cast<std::size_t>(b)];
    const Rows rows = band_rows(h, b, bands);
    if (level.L == nullptr) {
      to_unit_float_rows(level.image, *level.unit, rows.begin, rows.end);
      return;
    }
    if (level.R) {
      WorkVector<std::int32_t>* cand = nullptr;
      if (level.collect >= 0) {
        cand = &band.candidates[static_cast<std::size_t>(level.collect)];
        cand->clear();
        band.mask.resize(static_cast<std::size_t>(w) + 8);  // +8: the skip reads 8 bytes at a time
      }
      // One band reads no rows of another: no halo (none reserved with one thread).
      float* halo = nullptr;
      if (bands > 1 && (cand != nullptr || level.scan >= 0)) {
        band.halo.resize(w, 2);
        halo = band.halo.data();
      }
      const bool complete =
          hessian_band(L, level.norm, level.threshold, *level.R, rows.begin, rows.end, level.below,
                       band.mask.data(), halo, cand, max_candidate_ints_);
      if (cand != nullptr) band.complete[static_cast<std::size_t>(level.collect)] = complete;
      if (level.scan >= 0) {
        // The band's rows of the level above are done, and the rows around
        // them are in its halo: the level below's maxima in this band.
        const BandRows above{level.R, rows.begin, rows.end, halo,
                             halo != nullptr ? halo + w : nullptr};
        scan_level(band.candidates[static_cast<std::size_t>(level.scan)].data(),
                   kept_candidates(level.scan, b), *level.scan_lo, *level.scan_mid, above,
                   level.scan_info, level.max_keypoints,
                   b == 0 ? *level.strongest : band.strongest);
      }
    }
    if (level.blurred)
      gaussian_blur_rows(L, level.blur_sigma, *level.blurred, rows.begin, rows.end, band.scratch);
    if (level.halved) {
      const Rows half = band_rows(h / 2, b, bands);
      halve(L, *level.halved, half.begin, half.end);
    }
  };
  if (bands > 1) {
    workers_->run(bands, task);
  } else {
    task(0, 0);
  }
}

std::size_t HessianDetector::kept_candidates(int slot, int band) const {
  const auto s = static_cast<std::size_t>(slot);
  std::size_t room = max_candidate_ints_;
  for (int b = 0; b < band; ++b) {
    const Band& earlier = bands_[static_cast<std::size_t>(b)];
    const std::size_t n = earlier.candidates[s].size();
    if (!earlier.complete[s] || n >= room) return 0;
    room -= n;
  }
  return std::min(bands_[static_cast<std::size_t>(band)].candidates[s].size(), room);
}

bool HessianDetector::candidates_complete(int slot, int bands) const {
  const auto s = static_cast<std::size_t>(slot);
  std::size_t total = 0;
  for (int b = 0; b < bands; ++b) {
    const Band& band = bands_[static_cast<std::size_t>(b)];
    if (!band.complete[s]) return false;
    total += band.candidates[s].size();
  }
  return total <= max_candidate_ints_;
}

bool HessianDetector::detect(ImageView image, const KeypointParams& params, int max_keypoints,
                             WorkVector<Keypoint>& out) {
  out.clear();
  if (image.empty() || max_keypoints <= 0 || params.hessian_octaves <= 0) return true;
  for (Band& band : bands_) band.strongest.clear();
  bool complete = true;
  const int levels = std::max(1, params.hessian_levels);
  const double k = std::pow(2.0, 1.0 / levels);
  LevelInfo info;
  info.threshold = std::max(params.hessian_threshold, 0.f);  // maxima are always positive
  info.sigma0 = kSigma0;
  info.log_k = static_cast<float>(std::log(k));
  const int input_bands = bands_for(image.width, image.height);
  // Octave 0 may start below sigma0 (hessian_fine_levels: smaller blobs,
  // for small signs); its level j has sigma0 k^j from j = -fine.
  const int fine = std::clamp(params.hessian_fine_levels, 0, levels);
  const float fine_threshold =
      params.hessian_fine_threshold > 0.f ? params.hessian_fine_threshold : info.threshold;
  const double octave0_sigma = kSigma0 * std::pow(k, -fine);
  // Octave 0 starts at its first sigma from the input's assumed blur.
  Level convert;
  convert.image = image;
  convert.unit = &levels_[1];
  levels_[1].resize(image.width, image.height);
  run_level(convert, input_bands);
  Level input;
  input.L = &levels_[1];
  // In float, as without fine levels (the same keypoints, bit for bit).
  const auto s0 = static_cast<float>(octave0_sigma);
  input.blur_sigma = std::sqrt(s0 * s0 - kInputSigma * kInputSigma);
  input.blurred = &levels_[0];
  run_level(input, input_bands);

  const Plane<float>* first = &levels_[0];
  for (int octave = 0; octave < params.hessian_octaves; ++octave) {
    if (std::min(first->width(), first->height()) < 2 * kBorder + 3) break;
    info.octave_scale = std::ldexp(1.f, octave);
    const bool more = octave + 1 < params.hessian_octaves;
    const int bands = bands_for(first->width(), first->height());
    // Level j has sigma0 k^j (octave pixels); levels j0 and levels + 1 exist
    // only as scale neighbours of levels j0 + 1..levels.
    // After octave 0 the first level also carries halve()'s box blur.
    const int j0 = octave == 0 ? -fine : 0;
    const double first_sigma =
        octave == 0 ? octave0_sigma : std::sqrt(kSigma0 * kSigma0 + kHalvingVariance);
    const Plane<float>* cur = first;
    for (int j = j0; j <= levels + 1; ++j) {
      const int i = j - j0;  // the level's place in this octave: the rings' slot
      const double s_cur = j == j0 ? first_sigma : kSigma0 * std::pow(k, j);
      const auto sigma = static_cast<float>(s_cur);
      Level level;
      level.L = cur;
      level.norm = sigma * sigma * sigma * sigma;
      // The fine levels' maxima have a threshold of their own: at these
      // scales noise and texture peak too (docs/RESULTS.md, issue 38).
      level.threshold = j < 1 ? fine_threshold : info.threshold;
      level.R = &responses_[i % 3];
      if (i >= 1) level.below = &responses_[(i - 1) % 3];
      // Candidates only where maxima are taken: levels j0 + 1..levels.
      if (i >= 1 && j <= levels) level.collect = i % 2;
      // The level below's maxima, in this level's run: each band scans
      // what it collected there (the octave's bands are the same), reading
      // this level's response where it has just computed it.
      if (i >= 2) {
        level.scan = (i - 1) % 2;
        level.scan_lo = &responses_[(i - 2) % 3];
        level.scan_mid = &responses_[(i - 1) % 3];
        level.scan_info = info;
        level.scan_info.level = j - 1;
        level.max_keypoints = max_keypoints;
        level.strongest = &out;
      }
      // The next level, blurred from this one: Gaussians compose by adding
      // variances, so blur by the difference. Levels ping-pong between two
      // planes; octave 0's first level lives in levels_[0], which its third
      // level overwrites, so the next octave's first level gets its own plane.
      if (j <= levels) {
        const double s_next = kSigma0 * std::pow(k, j + 1);
        level.blur_sigma = static_cast<float>(std::sqrt(s_next * s_next - s_cur * s_cur));
        level.blurred = &levels_[(i + 1) % 2];
      }
      if (j == levels && more) level.halved = &next_octave_;
      run_level(level, bands);
      if (level.collect >= 0) complete &= candidates_complete(level.collect, bands);
      cur = level.blurred;
    }
    first = &next_octave_;
  }
  // The strongest of all are the strongest of each band's strongest
  // (`stronger` is a total order on distinct keypoints): the same whichever
  // band found them.
  const auto keep = static_cast<std::size_t>(max_keypoints);
  for (std::size_t b = 1; b < bands_.size(); ++b)
    for (const Keypoint& kp : bands_[b].strongest) offer_strongest(out, kp, keep, stronger);
  std::sort_heap(out.begin(), out.end(), stronger);
  return complete;
}

}  // namespace kg
