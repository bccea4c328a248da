// The inner loop of the model index's search: a kd-tree leaf of int8 tree
// points (kSearchDims components: the descriptor, then the scale
// attributes) compared with one query. It is most of a frame's search time,
// so it has vector versions (NEON on ARM, SSE2 on x86-64) beside the
// scalar one, which is the reference: both give identical results
// (tests/core/test_kdtree.cpp); simd_level() (keygraph/simd.h) chooses.
#pragma once

#include <cstdint>

#include "core/description/arc_types.h"
#include "keygraph/types.h"

namespace kg {

// Writes to hits[] the positions i in [0, n) of the points p[i] whose
// descriptor components are at squared distance < radius2 from q's and
// whose attributes are each within `box` of q's; returns how many.
// hits[] must have room for n rounded up to a multiple of 4: the vector
// code writes positions four at a time.
int scan_leaf_i8_scalar(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q,
                        std::int32_t radius2, std::int32_t box, std::uint16_t* hits);
// The same, vectorised where the target has NEON or SSE2 and simd_level()
// is not kScalar (else the scalar code).
int scan_leaf_i8(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q, std::int32_t radius2,
                 std::int32_t box, std::uint16_t* hits);
// How a ranked search (BasicKdTreeView::radius_search_approximate with a
// cap on its hits) orders the points it found: the rank code of a point is
// min(255, floor(float(d2) * descriptor + float(a2) * attribute)) in float
// arithmetic, d2 its squared descriptor distance and a2 the sum of its
// squared attribute differences from the query. The weights make a point
// at the radius and the box's corner rank 256 (ArcSearch: rank_weights()).
struct LeafRankWeights {
  float descriptor = 0.f;
  float attribute = 0.f;
};
// The rank code of one point (the reference for the vector code).
inline std::uint8_t leaf_rank_code(std::int32_t d2, std::int32_t a2, LeafRankWeights w) {
  const float r = static_cast<float>(d2) * w.descriptor + static_cast<float>(a2) * w.attribute;
  return r >= 255.f ? std::uint8_t{255} : static_cast<std::uint8_t>(r);
}
// scan_leaf_i8, also writing ranks[i], the rank code of point i, for every
// i in [0, n) (hit or not; ranks[] needs the room hits[] needs).
int scan_leaf_i8_ranked_scalar(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q,
                               std::int32_t radius2, std::int32_t box, LeafRankWeights weights,
                               std::uint16_t* hits, std::uint8_t* ranks);
// The same, vectorised on x86-64 (SSE2); the scalar code elsewhere.
int scan_leaf_i8_ranked(const ArcSearchPointI8* p, int n, const ArcSearchPointI8& q,
                        std::int32_t radius2, std::int32_t box, LeafRankWeights weights,
                        std::uint16_t* hits, std::uint8_t* ranks);
// Whether a leaf whose points lie in [bounds[0], bounds[1]] (component-wise)
// can hold a point within radius2 and box of q as scan_leaf_i8 tests them:
// the squared distance from q to the bounds' box over the descriptor
// components, each component's gap being lo - q when positive, else
// max(q - hi, 0), and each attribute's gap within `box`.
bool leaf_may_match_i8_scalar(const ArcSearchPointI8* bounds, const ArcSearchPointI8& q,
                              std::int32_t radius2, std::int32_t box);
// The same, vectorised like scan_leaf_i8.
bool leaf_may_match_i8(const ArcSearchPointI8* bounds, const ArcSearchPointI8& q,
                       std::int32_t radius2, std::int32_t box);
// Which implementation scan_leaf_i8 runs now: "neon", "sse2" or "scalar".
const char* leaf_scan_isa();

}  // namespace kg
