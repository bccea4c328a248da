#include "core/leaf_scan.h"

#if defined(__ARM_NEON) || defined(__ARM_NEON__)
#include <arm_neon.h>
#define KG_LEAF_NEON 1
#elif defined(__SSE2__)
#include <emmintrin.h>
#define KG_LEAF_SSE2 1
#endif

namespace kg {

static_assert(kSearchDims == 8 && kDescriptorSize == 6,
              "the vector code holds one point in 8 lanes: 6 descriptor, 2 attributes");

int scan_leaf_i8_scalar(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q,
                        std::int32_t radius2, std::int32_t box, std::uint16_t* hits) {
  int found = 0;
  for (int i = 0; i < n; ++i) {
    std::int32_t d2 = 0;
    for (int c = 0; c < kDescriptorSize; ++c) {
      const std::int32_t d = std::int32_t{p[i][c]} - std::int32_t{q[c]};
      d2 += d * d;
    }
    bool inside = d2 < radius2;
    for (int c = kDescriptorSize; c < kSearchDims; ++c) {
      const std::int32_t d = std::int32_t{p[i][c]} - std::int32_t{q[c]};
      inside = inside && (d < 0 ? -d : d) <= box;
    }
    if (inside) hits[found++] = static_cast<std::uint16_t>(i);
  }
  return found;
}

#if defined(KG_LEAF_NEON)

const char* leaf_scan_isa() {
  return "neon";
}

int scan_leaf_i8(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q, std::int32_t radius2,
                 std::int32_t box, std::uint16_t* hits) {
  const int8x8_t query = vld1_s8(q.data());
  // Differences are at most 254 in magnitude, so |d| <= box saturates
  // correctly at int16 for any box >= 254.
  const int16x4_t limit = vdup_n_s16(static_cast<std::int16_t>(box > 32767 ? 32767 : box));
  int found = 0;
  for (int i = 0; i < n; ++i) {
    const int16x8_t d = vsubl_s8(vld1_s8(p[i].data()), query);  // 8 x int16
    const int16x4_t lo = vget_low_s16(d), hi = vget_high_s16(d);
    // d0^2 + d1^2 + d2^2 + d3^2 and d4^2 + d5^2 (lanes 0, 1 of the high half).
    const int32x4_t sq_lo = vmull_s16(lo, lo);
    const int32x4_t sq_hi = vmull_s16(hi, hi);
    const int32x2_t pairs = vadd_s32(vget_low_s32(sq_lo), vget_high_s32(sq_lo));
    const std::int32_t d2 = vget_lane_s32(pairs, 0) + vget_lane_s32(pairs, 1) +
                            vgetq_lane_s32(sq_hi, 0) + vgetq_lane_s32(sq_hi, 1);
    const uint16x4_t within = vcle_s16(vabs_s16(hi), limit);  // lanes 2, 3: the attributes
    const bool inside =
        d2 < radius2 && vget_lane_u16(within, 2) != 0 && vget_lane_u16(within, 3) != 0;
    hits[found] = static_cast<std::uint16_t>(i);
    found += inside ? 1 : 0;
  }
  return found;
}

#elif defined(KG_LEAF_SSE2)

const char* leaf_scan_isa() {
  return "sse2";
}

namespace {

// Sign-extends the 8 int8 lanes of the low half of v to int16.
inline __m128i widen_low(__m128i v) {
  return _mm_srai_epi16(_mm_unpacklo_epi8(v, v), 8);
}
inline __m128i widen_high(__m128i v) {
  return _mm_srai_epi16(_mm_unpackhi_epi8(v, v), 8);
}

}  // namespace

int scan_leaf_i8(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q, std::int32_t radius2,
                 std::int32_t box, std::uint16_t* hits) {
  std::int64_t q64;
  __builtin_memcpy(&q64, q.data(), sizeof q64);
  const __m128i query = widen_low(_mm_set1_epi64x(q64));
  // Squares of lanes 0..5 only: the attribute lanes 6, 7 are masked out of
  // the sum and compared with the box instead.
  const __m128i descriptor_lanes = _mm_set_epi16(0, 0, -1, -1, -1, -1, -1, -1);
  const __m128i limit = _mm_set1_epi16(static_cast<short>(box > 32767 ? 32767 : box));
  int found = 0;
  int i = 0;
  for (; i + 1 < n; i += 2) {  // two points per 16 bytes
    const __m128i both = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p[i].data()));
    const __m128i d0 = _mm_sub_epi16(widen_low(both), query);
    const __m128i d1 = _mm_sub_epi16(widen_high(both), query);
    const __m128i m0 = _mm_and_si128(d0, descriptor_lanes);
    const __m128i m1 = _mm_and_si128(d1, descriptor_lanes);
    // madd: lanes (d0^2 + d1^2, d2^2 + d3^2, d4^2 + d5^2, 0) per point.
    const __m128i s0 = _mm_madd_epi16(m0, m0);
    const __m128i s1 = _mm_madd_epi16(m1, m1);
    // Horizontal sums: [a0 + a2, a1 + a3, b0 + b2, b1 + b3], then pairs.
    const __m128i t = _mm_add_epi32(_mm_unpacklo_epi64(s0, s1), _mm_unpackhi_epi64(s0, s1));
    const __m128i u = _mm_add_epi32(t, _mm_shuffle_epi32(t, _MM_SHUFFLE(2, 3, 0, 1)));
    const std::int32_t d2_0 = _mm_cvtsi128_si32(u);
    const std::int32_t d2_1 = _mm_cvtsi128_si32(_mm_unpackhi_epi64(u, u));
    // |d| <= box on the attribute lanes 6, 7: max(d, -d) compared.
    const __m128i a0 = _mm_max_epi16(d0, _mm_sub_epi16(_mm_setzero_si128(), d0));
    const __m128i a1 = _mm_max_epi16(d1, _mm_sub_epi16(_mm_setzero_si128(), d1));
    const int over0 = _mm_movemask_epi8(_mm_cmpgt_epi16(a0, limit)) & 0xF000;
    const int over1 = _mm_movemask_epi8(_mm_cmpgt_epi16(a1, limit)) & 0xF000;
    hits[found] = static_cast<std::uint16_t>(i);
    found += (d2_0 < radius2 && over0 == 0) ? 1 : 0;
    hits[found] = static_cast<std::uint16_t>(i + 1);
    found += (d2_1 < radius2 && over1 == 0) ? 1 : 0;
  }
  if (i < n) {
    std::uint16_t last;
    if (scan_leaf_i8_scalar(p + i, 1, q, radius2, box, &last) == 1)
      hits[found++] = static_cast<std::uint16_t>(i);
  }
  return found;
}

#else

const char* leaf_scan_isa() {
  return "scalar";
}

int scan_leaf_i8(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q, std::int32_t radius2,
                 std::int32_t box, std::uint16_t* hits) {
  return scan_leaf_i8_scalar(p, n, q, radius2, box, hits);
}

#endif

}  // namespace kg
