#include "core/index/leaf_scan.h"
#include "core/description/arc_types.h"

#include "core/support/simd_dispatch.h"

#if defined(KG_SIMD_NEON)
#include <arm_neon.h>
#define KG_LEAF_NEON 1
#elif defined(KG_SIMD_SSE2)
#include <emmintrin.h>
#define KG_LEAF_SSE2 1
#endif

namespace kg {

static_assert(kSearchDims == 8 && kDescriptorSize == 6,
              "the vector code holds one point in 8 lanes: 6 descriptor, 2 attributes");

#if defined(KG_LEAF_NEON) || defined(KG_LEAF_SSE2)
namespace {

// The box as an int16 lane limit. Differences are at most 254 in magnitude,
// so |d| <= box saturates correctly at int16 for any box >= 254.
inline std::int16_t box_limit(std::int32_t box) {
  return static_cast<std::int16_t>(box > 32767 ? 32767 : box);
}

}  // namespace
#endif

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

int scan_leaf_i8_ranked_scalar(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q,
                               std::int32_t radius2, std::int32_t box, LeafRankWeights weights,
                               std::uint16_t* hits, std::uint8_t* ranks) {
  int found = 0;
  for (int i = 0; i < n; ++i) {
    std::int32_t d2 = 0, a2 = 0;
    for (int c = 0; c < kDescriptorSize; ++c) {
      const std::int32_t d = std::int32_t{p[i][c]} - std::int32_t{q[c]};
      d2 += d * d;
    }
    bool inside = d2 < radius2;
    for (int c = kDescriptorSize; c < kSearchDims; ++c) {
      const std::int32_t d = std::int32_t{p[i][c]} - std::int32_t{q[c]};
      inside = inside && (d < 0 ? -d : d) <= box;
      a2 += d * d;
    }
    ranks[i] = leaf_rank_code(d2, a2, weights);
    if (inside) hits[found++] = static_cast<std::uint16_t>(i);
  }
  return found;
}

bool leaf_may_match_i8_scalar(const ArcSearchPointI8* bounds, const ArcSearchPointI8& q,
                              std::int32_t radius2, std::int32_t box) {
  std::int32_t d2 = 0;
  bool inside = true;
  for (int c = 0; c < kSearchDims; ++c) {
    const std::int32_t below = std::int32_t{bounds[0][c]} - std::int32_t{q[c]};
    const std::int32_t above = std::int32_t{q[c]} - std::int32_t{bounds[1][c]};
    const std::int32_t gap = below > 0 ? below : above > 0 ? above : 0;
    if (c < kDescriptorSize) {
      d2 += gap * gap;
    } else {
      inside = inside && gap <= box;
    }
  }
  return inside && d2 < radius2;
}

#if defined(KG_LEAF_NEON)

static const char* leaf_scan_vector_isa() {
  return "neon";
}

namespace {

// Whether the 8 int16 lanes of d (differences, or gaps to a box) lie within
// radius2 over the descriptor lanes 0..5 and within `limit` in magnitude on
// the attribute lanes 6, 7.
inline bool inside(int16x8_t d, std::int32_t radius2, int16x4_t limit) {
  const int16x4_t lo = vget_low_s16(d), hi = vget_high_s16(d);
  // d0^2 + d1^2 + d2^2 + d3^2 and d4^2 + d5^2 (lanes 0, 1 of the high half).
  const int32x4_t sq_lo = vmull_s16(lo, lo);
  const int32x4_t sq_hi = vmull_s16(hi, hi);
  const int32x2_t pairs = vadd_s32(vget_low_s32(sq_lo), vget_high_s32(sq_lo));
  const std::int32_t d2 = vget_lane_s32(pairs, 0) + vget_lane_s32(pairs, 1) +
                          vgetq_lane_s32(sq_hi, 0) + vgetq_lane_s32(sq_hi, 1);
  const uint16x4_t within = vcle_s16(vabs_s16(hi), limit);  // lanes 2, 3: the attributes
  return d2 < radius2 && vget_lane_u16(within, 2) != 0 && vget_lane_u16(within, 3) != 0;
}

}  // namespace

static int scan_leaf_i8_vector(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q,
                               std::int32_t radius2, std::int32_t box, std::uint16_t* hits) {
  const int8x8_t query = vld1_s8(q.data());
  const int16x4_t limit = vdup_n_s16(box_limit(box));
  int found = 0;
  for (int i = 0; i < n; ++i) {
    const int16x8_t d = vsubl_s8(vld1_s8(p[i].data()), query);  // 8 x int16
    hits[found] = static_cast<std::uint16_t>(i);
    found += inside(d, radius2, limit) ? 1 : 0;
  }
  return found;
}

static int scan_leaf_i8_ranked_vector(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q,
                                      std::int32_t radius2, std::int32_t box,
                                      LeafRankWeights weights, std::uint16_t* hits,
                                      std::uint8_t* ranks) {
  // scan_leaf_i8_vector with each point's attribute squares (the high
  // half's lanes 2, 3) summed beside its distance, and the rank code
  // computed by the reference's own function.
  const int8x8_t query = vld1_s8(q.data());
  const int16x4_t limit = vdup_n_s16(box_limit(box));
  int found = 0;
  for (int i = 0; i < n; ++i) {
    const int16x8_t d = vsubl_s8(vld1_s8(p[i].data()), query);
    const int16x4_t lo = vget_low_s16(d), hi = vget_high_s16(d);
    const int32x4_t sq_lo = vmull_s16(lo, lo);
    const int32x4_t sq_hi = vmull_s16(hi, hi);
    const int32x2_t pairs = vadd_s32(vget_low_s32(sq_lo), vget_high_s32(sq_lo));
    const std::int32_t d2 = vget_lane_s32(pairs, 0) + vget_lane_s32(pairs, 1) +
                            vgetq_lane_s32(sq_hi, 0) + vgetq_lane_s32(sq_hi, 1);
    const std::int32_t a2 = vgetq_lane_s32(sq_hi, 2) + vgetq_lane_s32(sq_hi, 3);
    const uint16x4_t within = vcle_s16(vabs_s16(hi), limit);
    ranks[i] = leaf_rank_code(d2, a2, weights);
    hits[found] = static_cast<std::uint16_t>(i);
    found += d2 < radius2 && vget_lane_u16(within, 2) != 0 && vget_lane_u16(within, 3) != 0 ? 1 : 0;
  }
  return found;
}

static bool leaf_may_match_i8_vector(const ArcSearchPointI8* bounds, const ArcSearchPointI8& q,
                                     std::int32_t radius2, std::int32_t box) {
  const int16x8_t query = vmovl_s8(vld1_s8(q.data()));
  const int16x8_t below = vsubq_s16(vmovl_s8(vld1_s8(bounds[0].data())), query);
  const int16x8_t above = vsubq_s16(query, vmovl_s8(vld1_s8(bounds[1].data())));
  const int16x8_t zero = vdupq_n_s16(0);
  // below where it is positive, else max(above, 0): never negative, so the
  // magnitude test on the attributes is the gap test.
  const int16x8_t gap = vbslq_s16(vcgtq_s16(below, zero), below, vmaxq_s16(above, zero));
  return inside(gap, radius2, vdup_n_s16(box_limit(box)));
}

#elif defined(KG_LEAF_SSE2)

static const char* leaf_scan_vector_isa() {
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

// For each 4-bit mask of matching points in a group: the positions of its
// set bits as four uint16 lanes, packed low first (unused lanes 0), and how
// many there are. Writing all four lanes and advancing by the count stores
// the hits without a branch per hit, which mispredicted on every group
// holding one (about a quarter of the search's mispredictions).
constexpr std::uint64_t compacted(int mask) {
  std::uint64_t lanes = 0;
  int n = 0;
  for (int b = 0; b < 4; ++b)
    if (mask & (1 << b)) lanes |= static_cast<std::uint64_t>(b) << (16 * n++);
  return lanes;
}
constexpr std::uint64_t kCompacted[16] = {
    compacted(0),  compacted(1),  compacted(2),  compacted(3), compacted(4),  compacted(5),
    compacted(6),  compacted(7),  compacted(8),  compacted(9), compacted(10), compacted(11),
    compacted(12), compacted(13), compacted(14), compacted(15)};
constexpr std::uint8_t kBitCount[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};

// One group of up to four int8 points against the query: their squared
// descriptor distances, their attribute differences and which of them are
// inside the ball and the box (bit per point; only the `left` first).
struct I8Group {
  __m128i d2;    // |descriptor difference|^2 of the four points
  __m128i attr;  // [a6 a7 b6 b7 c6 c7 d6 d7]: the attribute differences
  int inside;
};

inline __attribute__((always_inline)) I8Group test_i8_group(const ArcSearchPointI8* p, int i, int n,
                                                            __m128i query, __m128i limit,
                                                            __m128i r2) {
  // Squares of lanes 0..5 only: the attribute lanes 6, 7 are masked out of
  // the sum and compared with the box instead.
  const __m128i descriptor_lanes = _mm_set_epi16(0, 0, -1, -1, -1, -1, -1, -1);
  const __m128i zero = _mm_setzero_si128();
  // The last group may hold 1 to 3 points: load only those (8-byte loads
  // for a lone point), never past the leaf.
  const int left = n - i;
  const auto* bytes = reinterpret_cast<const __m128i*>(p[i].data());
  const __m128i x0 = left >= 2 ? _mm_loadu_si128(bytes) : _mm_loadl_epi64(bytes);
  const __m128i x1 = left >= 4   ? _mm_loadu_si128(bytes + 1)
                     : left == 3 ? _mm_loadl_epi64(bytes + 1)
                                 : zero;
  const __m128i a = _mm_sub_epi16(widen_low(x0), query);
  const __m128i b = _mm_sub_epi16(widen_high(x0), query);
  const __m128i c = _mm_sub_epi16(widen_low(x1), query);
  const __m128i d = _mm_sub_epi16(widen_high(x1), query);
  // madd of the descriptor lanes: (d0^2 + d1^2, d2^2 + d3^2, d4^2 + d5^2, 0).
  const __m128i ma = _mm_and_si128(a, descriptor_lanes), mb = _mm_and_si128(b, descriptor_lanes);
  const __m128i mc = _mm_and_si128(c, descriptor_lanes), md = _mm_and_si128(d, descriptor_lanes);
  const __m128i sa = _mm_madd_epi16(ma, ma), sb = _mm_madd_epi16(mb, mb);
  const __m128i sc = _mm_madd_epi16(mc, mc), sd = _mm_madd_epi16(md, md);
  // Transpose-and-add to [|a|^2, |b|^2, |c|^2, |d|^2].
  const __m128i ab = _mm_add_epi32(_mm_unpacklo_epi32(sa, sb), _mm_unpackhi_epi32(sa, sb));
  const __m128i cd = _mm_add_epi32(_mm_unpacklo_epi32(sc, sd), _mm_unpackhi_epi32(sc, sd));
  I8Group g;
  g.d2 = _mm_add_epi32(_mm_unpacklo_epi64(ab, cd), _mm_unpackhi_epi64(ab, cd));
  const __m128i ball = _mm_cmpgt_epi32(r2, g.d2);
  // A point is inside the box when neither of its two |differences|
  // exceeds it.
  g.attr = _mm_unpackhi_epi64(_mm_unpackhi_epi32(a, b), _mm_unpackhi_epi32(c, d));
  const __m128i magnitude = _mm_max_epi16(g.attr, _mm_sub_epi16(zero, g.attr));
  const __m128i within = _mm_cmpeq_epi32(_mm_cmpgt_epi16(magnitude, limit), zero);
  g.inside = _mm_movemask_ps(_mm_castsi128_ps(_mm_and_si128(ball, within)));
  if (left < 4) g.inside &= (1 << left) - 1;
  return g;
}

// Appends group i's inside points' positions to hits[found...]; found <= i,
// so the four lanes written end within the group's rounded-up end.
inline __attribute__((always_inline)) int append_hits(int inside, int i, std::uint16_t* hits,
                                                      int found) {
  const std::uint64_t positions =
      kCompacted[inside] + 0x0001000100010001ULL * static_cast<std::uint64_t>(i);
  __builtin_memcpy(hits + found, &positions, sizeof positions);
  return found + kBitCount[inside];
}

}  // namespace

static int scan_leaf_i8_vector(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q,
                               std::int32_t radius2, std::int32_t box, std::uint16_t* hits) {
  std::int64_t q64;
  __builtin_memcpy(&q64, q.data(), sizeof q64);
  const __m128i query = widen_low(_mm_set1_epi64x(q64));
  const __m128i limit = _mm_set1_epi16(box_limit(box));
  const __m128i r2 = _mm_set1_epi32(radius2);
  int found = 0;
  for (int i = 0; i < n; i += 4) {  // four points: 32 bytes, one 8-lane difference each
    found = append_hits(test_i8_group(p, i, n, query, limit, r2).inside, i, hits, found);
  }
  return found;
}

static int scan_leaf_i8_ranked_vector(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q,
                                      std::int32_t radius2, std::int32_t box,
                                      LeafRankWeights weights, std::uint16_t* hits,
                                      std::uint8_t* ranks) {
  // scan_leaf_i8_vector with each group's four rank codes computed beside
  // its distances: the attributes' squares by one madd, the codes in float
  // as leaf_rank_code() computes them (no fused multiply-add in the core).
  std::int64_t q64;
  __builtin_memcpy(&q64, q.data(), sizeof q64);
  const __m128i query = widen_low(_mm_set1_epi64x(q64));
  const __m128i limit = _mm_set1_epi16(box_limit(box));
  const __m128i r2 = _mm_set1_epi32(radius2);
  const __m128i zero = _mm_setzero_si128();
  const __m128 wd = _mm_set1_ps(weights.descriptor);
  const __m128 wa = _mm_set1_ps(weights.attribute);
  const __m128 top = _mm_set1_ps(255.f);
  int found = 0;
  for (int i = 0; i < n; i += 4) {
    const I8Group g = test_i8_group(p, i, n, query, limit, r2);
    // (a6^2 + a7^2, b6^2 + b7^2, c6^2 + c7^2, d6^2 + d7^2).
    const __m128i a2 = _mm_madd_epi16(g.attr, g.attr);
    const __m128 rank = _mm_min_ps(
        _mm_add_ps(_mm_mul_ps(_mm_cvtepi32_ps(g.d2), wd), _mm_mul_ps(_mm_cvtepi32_ps(a2), wa)),
        top);
    const __m128i codes = _mm_cvttps_epi32(rank);  // 0..255
    const __m128i bytes4 = _mm_packus_epi16(_mm_packs_epi32(codes, zero), zero);
    const int packed = _mm_cvtsi128_si32(bytes4);
    __builtin_memcpy(ranks + i, &packed, sizeof packed);
    found = append_hits(g.inside, i, hits, found);
  }
  return found;
}

static bool leaf_may_match_i8_vector(const ArcSearchPointI8* bounds, const ArcSearchPointI8& q,
                                     std::int32_t radius2, std::int32_t box) {
  std::int64_t q64, lo64, hi64;
  __builtin_memcpy(&q64, q.data(), sizeof q64);
  __builtin_memcpy(&lo64, bounds[0].data(), sizeof lo64);
  __builtin_memcpy(&hi64, bounds[1].data(), sizeof hi64);
  const __m128i query = widen_low(_mm_set1_epi64x(q64));
  const __m128i below = _mm_sub_epi16(widen_low(_mm_set1_epi64x(lo64)), query);
  const __m128i above = _mm_sub_epi16(query, widen_low(_mm_set1_epi64x(hi64)));
  const __m128i zero = _mm_setzero_si128();
  // below where it is positive, else max(above, 0).
  const __m128i positive = _mm_cmpgt_epi16(below, zero);
  const __m128i gap = _mm_or_si128(_mm_and_si128(positive, below),
                                   _mm_andnot_si128(positive, _mm_max_epi16(above, zero)));
  const __m128i descriptor_lanes = _mm_set_epi16(0, 0, -1, -1, -1, -1, -1, -1);
  const __m128i masked = _mm_and_si128(gap, descriptor_lanes);
  const __m128i sums =
      _mm_madd_epi16(masked, masked);  // (g0^2 + g1^2, g2^2 + g3^2, g4^2 + g5^2, 0)
  const __m128i pair = _mm_add_epi32(sums, _mm_shuffle_epi32(sums, _MM_SHUFFLE(1, 0, 3, 2)));
  const __m128i total = _mm_add_epi32(pair, _mm_shuffle_epi32(pair, _MM_SHUFFLE(2, 3, 0, 1)));
  const std::int32_t d2 = _mm_cvtsi128_si32(total);
  const __m128i limit = _mm_set1_epi16(box_limit(box));
  const int outside = _mm_movemask_epi8(_mm_cmpgt_epi16(gap, limit)) & 0xF000;  // lanes 6, 7
  return outside == 0 && d2 < radius2;
}

#else

static const char* leaf_scan_vector_isa() {
  return "scalar";
}

static int scan_leaf_i8_vector(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q,
                               std::int32_t radius2, std::int32_t box, std::uint16_t* hits) {
  return scan_leaf_i8_scalar(p, n, q, radius2, box, hits);
}

static bool leaf_may_match_i8_vector(const ArcSearchPointI8* bounds, const ArcSearchPointI8& q,
                                     std::int32_t radius2, std::int32_t box) {
  return leaf_may_match_i8_scalar(bounds, q, radius2, box);
}

#endif

#if !defined(KG_LEAF_SSE2) && !defined(KG_LEAF_NEON)
// Without vector code: the reference.
static int scan_leaf_i8_ranked_vector(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q,
                                      std::int32_t radius2, std::int32_t box,
                                      LeafRankWeights weights, std::uint16_t* hits,
                                      std::uint8_t* ranks) {
  return scan_leaf_i8_ranked_scalar(p, n, q, radius2, box, weights, hits, ranks);
}
#endif

const char* leaf_scan_isa() {
  return simd_level() == SimdLevel::kScalar ? "scalar" : leaf_scan_vector_isa();
}

int scan_leaf_i8(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q, std::int32_t radius2,
                 std::int32_t box, std::uint16_t* hits) {
  if (simd_level() == SimdLevel::kScalar) return scan_leaf_i8_scalar(p, n, q, radius2, box, hits);
  return scan_leaf_i8_vector(p, n, q, radius2, box, hits);
}

int scan_leaf_i8_ranked(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q,
                        std::int32_t radius2, std::int32_t box, LeafRankWeights weights,
                        std::uint16_t* hits, std::uint8_t* ranks) {
  if (simd_level() == SimdLevel::kScalar)
    return scan_leaf_i8_ranked_scalar(p, n, q, radius2, box, weights, hits, ranks);
  return scan_leaf_i8_ranked_vector(p, n, q, radius2, box, weights, hits, ranks);
}

bool leaf_may_match_i8(const ArcSearchPointI8* bounds, const ArcSearchPointI8& q,
                       std::int32_t radius2, std::int32_t box) {
  if (simd_level() == SimdLevel::kScalar) return leaf_may_match_i8_scalar(bounds, q, radius2, box);
  return leaf_may_match_i8_vector(bounds, q, radius2, box);
}

}  // namespace kg
