// Delaunay triangulation of a planar point set in O(n log n) expected time
// (radial sweep-hull followed by edge flips).
//
// Output convention: triangles() holds 3 vertex indices per triangle, each
// triangle (a, b, c) with orient(a, b, c) > 0 where
//   orient(a, b, c) = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x),
// i.e. clockwise as seen on screen with y pointing down. Half-edge e runs
// from triangles()[e] to triangles()[next(e)] inside triangle e / 3;
// halfedges()[e] is the opposite half-edge in the neighbouring triangle, or
// -1 on the convex hull. Duplicate points are skipped (they appear in no
// triangle); fewer than 3 points or all points collinear give no triangles.
#pragma once

#include <cstdint>
#include <vector>

#include "core/support/workspace.h"
#include "keygraph/types.h"

namespace kg {

class Delaunay {
 public:
  explicit Delaunay(std::pmr::memory_resource* memory = std::pmr::get_default_resource());
  // Sizes every buffer for up to max_points points: triangulate() then
  // allocates nothing.
  void reserve(int max_points);
  // Triangulates points[0..n). Buffers are kept between calls and reused.
  void triangulate(const Point2f* points, int n);

  const WorkVector<int>& triangles() const { return triangles_; }
  const WorkVector<int>& halfedges() const { return halfedges_; }
  int triangle_count() const { return static_cast<int>(triangles_.size() / 3); }

  static int next(int e) { return (e % 3 == 2) ? e - 2 : e + 1; }
  static int prev(int e) { return (e % 3 == 0) ? e + 2 : e - 1; }

 private:
  WorkVector<int> triangles_;
  WorkVector<int> halfedges_;
  // Working storage (hull linked list, hash, sort order, flip stack ...).
  WorkVector<int> ids_;
  WorkVector<double> dists_;
  WorkVector<int> hull_prev_;
  WorkVector<int> hull_next_;
  WorkVector<int> hull_tri_;
  WorkVector<int> hull_hash_;
  WorkVector<int> edge_stack_;
};

}  // namespace kg
