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
