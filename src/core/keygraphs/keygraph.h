// Keygraph structures (paper section 5, Fig. 6): a 2-vertex arc, and 3- and
// 4-vertex circuits whose keytuple matrix is the cyclic successor matrix
// (sigma_ij = 1 iff j == i + 1 mod k). For circuits a keytuple is any cyclic
// rotation of another, so keytuples are stored implicitly: an ordered
// k-tuple of model keypoints is a model keytuple iff every consecutive pair
// (v_i, v_{i+1 mod k}) is a model arc (Chebyshev distance within
// [min, max]) and the circuit turns clockwise on screen at every vertex.
#pragma once

#include <cstdint>
#include <vector>

#include "core/keygraphs/delaunay.h"
#include "core/support/workspace.h"
#include "keygraph/params.h"
#include "keygraph/types.h"

namespace kg {

inline constexpr int kMaxVertices = 4;

// > 0 when a -> b -> c turns clockwise on screen (image y axis down).
inline float orient(Point2f a, Point2f b, Point2f c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

inline int vertex_count(Structure s) {
  return static_cast<int>(s);
}

// Keygraph correspondences needed for one homography (4 point pairs): h in
// the paper's log(1-P)/log(1-p^h).
inline int sample_size(Structure s) {
  return (4 + vertex_count(s) - 1) / vertex_count(s);
}

// The paper's relative-positioning criterion: for circuits every turn is
// clockwise (a convex clockwise polygon); arcs always pass.
bool is_clockwise_circuit(const Point2f* v, int k);

// Keytuple matrix sigma of a structure, row-major k x k (tests and docs).
void keytuple_matrix(Structure s, std::uint8_t* sigma);

// Whether (v_0..v_{k-1}) is a keytuple of graph with arcs `arcs` (pairs of
// positions into v) with respect to sigma: sigma_ij = 1 iff (v_i, v_j) is an arc.
bool is_keytuple(const int* order, int k, const std::uint8_t* sigma, const int* arc_from,
                 const int* arc_to, int arc_count);

// A scene keygraph as one keytuple of Delaunay half-edges: vertex i is the
// origin of half-edge edges[i] and the keytuple's arc (v_i, v_{i+1}) is that
// half-edge. For arcs edges[1] is next(edges[0]), only for its origin (the
// arc's target): the one looked-up arc is edges[0].
struct SceneKeygraph {
  std::int32_t edges[kMaxVertices];
};

// Scene keygraphs of the triangulation (paper section 5): one per edge (arc
// structure; one direction per edge), per face (3-circuit), or per internal
// edge for the 4-circuit formed by its two faces (skipped when that
// quadrilateral is not convex, as the model side holds only convex ones).
void scene_keygraphs(const Delaunay& dt, const Point2f* points, Structure structure,
                     WorkVector<SceneKeygraph>& out);

// Number of model keygraphs of one model (for reports): circuits whose arcs
// are all model arcs. Model arcs from keypoint a are to[offsets[a] ..
// offsets[a + 1]) (local ids), sorted.
std::uint64_t count_model_keygraphs(const Point2f* points, int n, const std::uint32_t* offsets,
                                    const std::uint32_t* to, const GraphParams& params);

inline bool is_model_arc(Point2f a, Point2f b, const GraphParams& p) {
  const float dx = a.x > b.x ? a.x - b.x : b.x - a.x;
  const float dy = a.y > b.y ? a.y - b.y : b.y - a.y;
  const float d = dx > dy ? dx : dy;
  return d >= p.min_distance && d <= p.max_distance;
}

// The same, also within max_relative_length detector scales of both ends
// (scales <= 0 are unknown and not checked).
inline bool is_model_arc(Point2f a, Point2f b, float scale_a, float scale_b, const GraphParams& p) {
  if (!is_model_arc(a, b, p)) return false;
  if (p.max_relative_length <= 0.f) return true;
  const float l2 = (b.x - a.x) * (b.x - a.x) + (b.y - a.y) * (b.y - a.y);
  const float ra = p.max_relative_length * scale_a, rb = p.max_relative_length * scale_b;
  return (scale_a <= 0.f || l2 <= ra * ra) && (scale_b <= 0.f || l2 <= rb * rb);
}

}  // namespace kg
