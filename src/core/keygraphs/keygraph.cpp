#include "core/keygraphs/keygraph.h"

#include <algorithm>

namespace kg {

bool is_clockwise_circuit(const Point2f* v, int k) {
  if (k < 3) return true;
  for (int i = 0; i < k; ++i) {
    if (!(orient(v[i], v[(i + 1) % k], v[(i + 2) % k]) > 0.f)) return false;
  }
  return true;
}

void keytuple_matrix(Structure s, std::uint8_t* sigma) {
  const int k = vertex_count(s);
  for (int i = 0; i < k; ++i) {
    for (int j = 0; j < k; ++j) sigma[i * k + j] = 0;
  }
  if (k == 2) {
    sigma[1] = 1;
    return;
  }
  for (int i = 0; i < k; ++i) sigma[i * k + (i + 1) % k] = 1;
}

bool is_keytuple(const int* order, int k, const std::uint8_t* sigma, const int* arc_from,
                 const int* arc_to, int arc_count) {
  for (int i = 0; i < k; ++i) {
    for (int j = 0; j < k; ++j) {
      if (i == j) continue;
      bool arc = false;
      for (int a = 0; a < arc_count && !arc; ++a)
        arc = arc_from[a] == order[i] && arc_to[a] == order[j];
      if (arc != (sigma[i * k + j] != 0)) return false;
    }
  }
  return true;
}

void scene_keygraphs(const Delaunay& dt, const Point2f* points, Structure structure,
                     WorkVector<SceneKeygraph>& out) {
  out.clear();
  const WorkVector<int>& tri = dt.triangles();
  const WorkVector<int>& half = dt.halfedges();
  const int edges = static_cast<int>(tri.size());
  switch (structure) {
    case Structure::kArc:
      for (int e = 0; e < edges; ++e) {
        if (half[e] < 0 || e < half[e]) out.push_back({{e, Delaunay::next(e), -1, -1}});
      }
      break;
    case Structure::kCircuit3:
      // Delaunay faces are already clockwise on screen (delaunay.h).
      for (int t = 0; t < edges; t += 3) out.push_back({{t, t + 1, t + 2, -1}});
      break;
    case Structure::kCircuit4:
      for (int e = 0; e < edges; ++e) {
        const int o = half[e];
        if (o < 0 || o < e) continue;
        // e: u -> v in face (u, v, w1); o: v -> u in face (v, u, w2). The
        // quadrilateral u -> w2 -> v -> w1 keeps both faces' orientation.
        const int u_w2 = Delaunay::next(o);
        const int w2_v = Delaunay::prev(o);
        const int v_w1 = Delaunay::next(e);
        const int w1_u = Delaunay::prev(e);
        const Point2f q[4] = {points[tri[u_w2]], points[tri[w2_v]], points[tri[v_w1]],
                              points[tri[w1_u]]};
        if (!is_clockwise_circuit(q, 4)) continue;
        out.push_back({{u_w2, w2_v, v_w1, w1_u}});
      }
      break;
  }
}

std::uint64_t count_model_keygraphs(const Point2f* p, int n, const std::uint32_t* offsets,
                                    const std::uint32_t* to, const GraphParams& params) {
  // Arcs leaving each keypoint are sorted by target.
  auto has_arc = [&](std::uint32_t from, std::uint32_t target) {
    return std::binary_search(to + offsets[from], to + offsets[from + 1], target);
  };
  std::uint64_t count = 0;
  const int k = vertex_count(params.structure);
  // A circuit is counted from its smallest vertex only (one of its k
  // rotations), which also prunes most paths early.
  for (std::uint32_t a = 0; a < static_cast<std::uint32_t>(n); ++a) {
    for (std::uint32_t i = offsets[a]; i < offsets[a + 1]; ++i) {
      const std::uint32_t b = to[i];
      if (k == 2) {
        ++count;
        continue;
      }
      if (b < a) continue;
      for (std::uint32_t j = offsets[b]; j < offsets[b + 1]; ++j) {
        const std::uint32_t c = to[j];
        if (c <= a || !(orient(p[a], p[b], p[c]) > 0.f)) continue;
        if (k == 3) {
          if (has_arc(c, a)) ++count;
          continue;
        }
        for (std::uint32_t l = offsets[c]; l < offsets[c + 1]; ++l) {
          const std::uint32_t d = to[l];
          if (d <= a || d == b || !(orient(p[b], p[c], p[d]) > 0.f)) continue;
          if (!(orient(p[c], p[d], p[a]) > 0.f) || !(orient(p[d], p[a], p[b]) > 0.f)) continue;
          if (has_arc(d, a)) ++count;
        }
      }
    }
  }
  return count;
}

}  // namespace kg
