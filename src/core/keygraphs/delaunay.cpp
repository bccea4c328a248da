#include "core/keygraphs/delaunay.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

// Radial sweep-hull Delaunay triangulation.
//
// Points are inserted in order of distance from the circumcentre of a small
// seed triangle, so every new point lies outside the current convex hull. It
// is joined to the hull edges it sees, and each new triangle is legalised by
// edge flips (Lawson). A hash of hull vertices by pseudo-angle around the
// centre finds a visible hull edge in expected O(1).
//
// All triangles are counter-clockwise in the y-up sense (orient > 0, see the
// header). Half-edge e runs from triangles_[e] to triangles_[next(e)] with the
// triangle on its left, so the hull, kept as a circular list through
// hull_next_, also runs counter-clockwise and hull_tri_[v] is the half-edge
// v -> hull_next_[v].

namespace kg {
namespace {

// ---- Predicates -----------------------------------------------------------
// A floating-point filter (Shewchuk's static bounds) decides almost every
// case; the rest are evaluated exactly with floating-point expansions. The
// exact path assumes coordinate differences are exact in double, which holds
// for float inputs whose magnitudes lie within 2^29 of each other (image
// coordinates). Exact predicates keep flips from cycling on cocircular input.

constexpr double kHalfUlp = 1.1102230246251565e-16;  // 2^-53
constexpr double kOrientErrBound = (3.0 + 16.0 * kHalfUlp) * kHalfUlp;
constexpr double kInCircleErrBound = (10.0 + 96.0 * kHalfUlp) * kHalfUlp;

// x + y == a + b exactly, with y the rounding error of x.
inline void TwoSum(double a, double b, double& x, double& y) {
  x = a + b;
  const double bv = x - a;
  const double av = x - bv;
  y = (a - av) + (b - bv);
}

// x + y == a * b exactly (fma gives the exact residual, and is immune to
// compiler contraction, unlike Dekker splitting).
inline void TwoProduct(double a, double b, double& x, double& y) {
  x = a * b;
  y = std::fma(a, b, -x);
}

// h = e + b for a nonoverlapping expansion e (ascending magnitude); zero
// components are dropped. Returns the length of h (at most elen + 1).
int GrowExpansion(int elen, const double* e, double b, double* h) {
  double q = b;
  int hlen = 0;
  for (int i = 0; i < elen; ++i) {
    double sum, err;
    TwoSum(q, e[i], sum, err);
    q = sum;
    if (err != 0.0) h[hlen++] = err;
  }
  if (q != 0.0 || hlen == 0) h[hlen++] = q;
  return hlen;
}

// h = e * b. Returns the length of h (at most 2 * elen).
int ScaleExpansion(int elen, const double* e, double b, double* h) {
  int hlen = 0;
  double q, err;
  TwoProduct(e[0], b, q, err);
  if (err != 0.0) h[hlen++] = err;
  for (int i = 1; i < elen; ++i) {
    double p1, p0, sum;
    TwoProduct(e[i], b, p1, p0);
    TwoSum(q, p0, sum, err);
    if (err != 0.0) h[hlen++] = err;
    TwoSum(p1, sum, q, err);
    if (err != 0.0) h[hlen++] = err;
  }
  if (q != 0.0 || hlen == 0) h[hlen++] = q;
  return hlen;
}

// h += f in place; tmp must hold hlen + flen values.
void AddExpansion(int& hlen, double* h, int flen, const double* f, double* tmp) {
  for (int i = 0; i < flen; ++i) {
    hlen = GrowExpansion(hlen, h, f[i], tmp);
    std::copy(tmp, tmp + hlen, h);
  }
}

// u * v for two expansions of at most 4 components each (result <= 32).
int MultiplySmall(int ulen, const double* u, int vlen, const double* v, double* h) {
  double scaled[8];
  double tmp[40];
  int hlen = 1;
  h[0] = 0.0;
  for (int i = 0; i < ulen; ++i) {
    const int slen = ScaleExpansion(vlen, v, u[i], scaled);
    AddExpansion(hlen, h, slen, scaled, tmp);
  }
  return hlen;
}

// a * b - c * d as an expansion of at most 4 components.
int CrossExpansion(double a, double b, double c, double d, double* h) {
  double x1, y1, x2, y2;
  TwoProduct(a, b, x1, y1);
  TwoProduct(c, d, x2, y2);
  const double e[2] = {y1, x1};
  double t[3];
  const int tlen = GrowExpansion(2, e, -y2, t);
  return GrowExpansion(tlen, t, -x2, h);
}

inline double Sign(double v) {
  return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0);
}

// orient(a, b, c) as defined in the header; only its sign is exact.
double Orient(const Point2f& a, const Point2f& b, const Point2f& c) {
  const double abx = static_cast<double>(b.x) - a.x;
  const double aby = static_cast<double>(b.y) - a.y;
  const double acx = static_cast<double>(c.x) - a.x;
  const double acy = static_cast<double>(c.y) - a.y;
  const double left = abx * acy;
  const double right = aby * acx;
  const double det = left - right;
  const double bound = kOrientErrBound * (std::abs(left) + std::abs(right));
  if (det > bound || -det > bound) return det;
  double h[4];
  const int hlen = CrossExpansion(abx, acy, aby, acx, h);
  return Sign(h[hlen - 1]);
}

// Positive when d lies strictly inside the circle through a, b, c, which must
// satisfy orient(a, b, c) > 0; zero when cocircular. Only the sign is exact.
double InCircle(const Point2f& a, const Point2f& b, const Point2f& c, const Point2f& d) {
  const double adx = static_cast<double>(a.x) - d.x;
  const double ady = static_cast<double>(a.y) - d.y;
  const double bdx = static_cast<double>(b.x) - d.x;
  const double bdy = static_cast<double>(b.y) - d.y;
  const double cdx = static_cast<double>(c.x) - d.x;
  const double cdy = static_cast<double>(c.y) - d.y;

  const double bdxcdy = bdx * cdy;
  const double cdxbdy = cdx * bdy;
  const double cdxady = cdx * ady;
  const double adxcdy = adx * cdy;
  const double adxbdy = adx * bdy;
  const double bdxady = bdx * ady;
  const double alift = adx * adx + ady * ady;
  const double blift = bdx * bdx + bdy * bdy;
  const double clift = cdx * cdx + cdy * cdy;
  const double det =
      alift * (bdxcdy - cdxbdy) + blift * (cdxady - adxcdy) + clift * (adxbdy - bdxady);
  const double permanent = (std::abs(bdxcdy) + std::abs(cdxbdy)) * alift +
                           (std::abs(cdxady) + std::abs(adxcdy)) * blift +
                           (std::abs(adxbdy) + std::abs(bdxady)) * clift;
  const double bound = kInCircleErrBound * permanent;
  if (det > bound || -det > bound) return det;

  // Exact: sum over the three rows of lift * cross, each at most 32 terms.
  double lift[4], cross[4], term[32], total[96], tmp[96];
  int lift_len = CrossExpansion(adx, adx, ady, -ady, lift);
  int cross_len = CrossExpansion(bdx, cdy, cdx, bdy, cross);
  int total_len = MultiplySmall(lift_len, lift, cross_len, cross, total);

  lift_len = CrossExpansion(bdx, bdx, bdy, -bdy, lift);
  cross_len = CrossExpansion(cdx, ady, adx, cdy, cross);
  int term_len = MultiplySmall(lift_len, lift, cross_len, cross, term);
  AddExpansion(total_len, total, term_len, term, tmp);

  lift_len = CrossExpansion(cdx, cdx, cdy, -cdy, lift);
  cross_len = CrossExpansion(adx, bdy, bdx, ady, cross);
  term_len = MultiplySmall(lift_len, lift, cross_len, cross, term);
  AddExpansion(total_len, total, term_len, term, tmp);
  return Sign(total[total_len - 1]);
}

// ---- Sweep ------------------------------------------------------------------

inline bool Finite(const Point2f& p) {
  return std::isfinite(p.x) && std::isfinite(p.y);
}

inline double Dist2(const Point2f& a, const Point2f& b) {
  const double dx = static_cast<double>(a.x) - b.x;
  const double dy = static_cast<double>(a.y) - b.y;
  return dx * dx + dy * dy;
}

// Squared distance below which a point counts as a duplicate ((1e-9)^2).
constexpr double kDuplicateDist2 = 1e-18;

// Squared circumradius of (a, b, c); infinite or NaN when (nearly) collinear.
double Circumradius2(const Point2f& a, const Point2f& b, const Point2f& c) {
  const double bx = static_cast<double>(b.x) - a.x;
  const double by = static_cast<double>(b.y) - a.y;
  const double cx = static_cast<double>(c.x) - a.x;
  const double cy = static_cast<double>(c.y) - a.y;
  const double bl = bx * bx + by * by;
  const double cl = cx * cx + cy * cy;
  const double d = 0.5 / (bx * cy - by * cx);
  const double x = (cy * bl - by * cl) * d;
  const double y = (bx * cl - cx * bl) * d;
  return x * x + y * y;
}

void Circumcenter(const Point2f& a, const Point2f& b, const Point2f& c, double& ox, double& oy) {
  const double bx = static_cast<double>(b.x) - a.x;
  const double by = static_cast<double>(b.y) - a.y;
  const double cx = static_cast<double>(c.x) - a.x;
  const double cy = static_cast<double>(c.y) - a.y;
  const double bl = bx * bx + by * by;
  const double cl = cx * cx + cy * cy;
  const double d = 0.5 / (bx * cy - by * cx);
  ox = a.x + (cy * bl - by * cl) * d;
  oy = a.y + (bx * cl - cx * bl) * d;
}

// Working state of one triangulate() call; all storage belongs to Delaunay.
struct Sweep {
  const Point2f* pts;
  WorkVector<int>& triangles;
  WorkVector<int>& halfedges;
  WorkVector<int>& hull_prev;
  WorkVector<int>& hull_next;
  WorkVector<int>& hull_tri;
  WorkVector<int>& hull_hash;
  WorkVector<int>& edge_stack;
  double cx = 0.0;
  double cy = 0.0;
  int hash_size = 1;
  int max_flips = 0;

  // Bucket of the pseudo-angle of p around the centre; the pseudo-angle grows
  // monotonically counter-clockwise, like the hull list.
  int HashKey(const Point2f& p) const {
    const double dx = p.x - cx;
    const double dy = p.y - cy;
    const double den = std::abs(dx) + std::abs(dy);
    if (!(den > 0.0)) return 0;
    const double q = dx / den;
    const double angle = (dy > 0.0 ? 3.0 - q : 1.0 + q) * 0.25;  // [0, 1]
    const double scaled = std::floor(angle * hash_size);
    if (!(scaled > 0.0)) return 0;
    const int key = static_cast<int>(std::min(scaled, static_cast<double>(hash_size)));
    return key % hash_size;
  }

  void Link(int a, int b) {
    halfedges[a] = b;
    if (b != -1) halfedges[b] = a;
  }

  int AddTriangle(int i0, int i1, int i2, int h0, int h1, int h2) {
    const int t = static_cast<int>(triangles.size());
    triangles.push_back(i0);
    triangles.push_back(i1);
    triangles.push_back(i2);
    halfedges.push_back(-1);
    halfedges.push_back(-1);
    halfedges.push_back(-1);
    Link(t, h0);
    Link(t + 1, h1);
    Link(t + 2, h2);
    return t;
  }

  // Restores the Delaunay property around a new point p after half-edge a
  // (opposite p in a new triangle) was created, flipping edges depth-first.
  void Legalize(int a) {
    edge_stack.clear();
    int flips = 0;
    while (true) {
      const int b = halfedges[a];
      const int a0 = a - a % 3;
      const int an = a0 + (a + 1) % 3;
      const int ar = a0 + (a + 2) % 3;
      bool flipped = false;
      if (b != -1) {
        const int b0 = b - b % 3;
        const int bn = b0 + (b + 1) % 3;
        const int bp = b0 + (b + 2) % 3;
        const int p0 = triangles[ar];  // the new point
        const int pr = triangles[a];
        const int pl = triangles[an];
        const int p1 = triangles[bp];  // apex of the neighbour across a
        // Exact arithmetic bounds flips per insertion by p's final degree;
        // the cap only guards against a cycle should that ever break down.
        if (flips < max_flips && InCircle(pts[pr], pts[pl], pts[p0], pts[p1]) > 0.0) {
          ++flips;
          flipped = true;
          // Quad pr, p1, pl, p0 (counter-clockwise): replace diagonal pr-pl by
          // p0-p1, reusing both triangle slots: a's becomes (p1, pl, p0), b's
          // becomes (p0, pr, p1).
          triangles[a] = p1;
          triangles[b] = p0;
          const int h_bp = halfedges[bp];  // twin of p1 -> pl, now slot a
          const int h_ar = halfedges[ar];  // twin of p0 -> pr, now slot b
          // A hull edge moved to another slot: keep hull_tri pointing at it.
          if (h_bp == -1 && hull_tri[p1] == bp) hull_tri[p1] = a;
          if (h_ar == -1 && hull_tri[p0] == ar) hull_tri[p0] = b;
          Link(a, h_bp);
          Link(b, h_ar);
          Link(ar, bp);
          // Both new triangles have an edge opposite p to check: a (same slot,
          // now p1 -> pl) next, and pr -> p1 later.
          edge_stack.push_back(bn);
        }
      }
      if (!flipped) {
        if (edge_stack.empty()) break;
        a = edge_stack.back();
        edge_stack.pop_back();
      }
    }
  }
};

}  // namespace

Delaunay::Delaunay(std::pmr::memory_resource* memory)
    : triangles_(memory),
      halfedges_(memory),
      ids_(memory),
      dists_(memory),
      hull_prev_(memory),
      hull_next_(memory),
      hull_tri_(memory),
      hull_hash_(memory),
      edge_stack_(memory) {}

namespace {

int hash_size_for(int n) {
  return std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n)))));
}

}  // namespace

void Delaunay::reserve(int max_points) {
  const auto n = static_cast<std::size_t>(std::max(0, max_points));
  triangles_.reserve(6 * n);
  halfedges_.reserve(6 * n);
  ids_.reserve(n);
  dists_.reserve(n);
  hull_prev_.reserve(n);
  hull_next_.reserve(n);
  hull_tri_.reserve(n);
  hull_hash_.reserve(static_cast<std::size_t>(hash_size_for(max_points)));
  edge_stack_.reserve(n + 3);  // Legalize() flips at most n + 3 times per point
}

void Delaunay::triangulate(const Point2f* points, int n) {
  triangles_.clear();
  halfedges_.clear();
  if (points == nullptr || n < 3) return;

  // Seed: the point nearest the bounding-box centre, its nearest neighbour,
  // and the point making the smallest circumcircle with them. With i1 the
  // nearest neighbour of i0 no point lies strictly inside that circle, so
  // sorting by distance from its centre keeps every new point outside the
  // hull built so far.
  double min_x = std::numeric_limits<double>::infinity();
  double min_y = min_x;
  double max_x = -min_x;
  double max_y = -min_x;
  for (int i = 0; i < n; ++i) {
    if (!Finite(points[i])) continue;
    min_x = std::min(min_x, static_cast<double>(points[i].x));
    min_y = std::min(min_y, static_cast<double>(points[i].y));
    max_x = std::max(max_x, static_cast<double>(points[i].x));
    max_y = std::max(max_y, static_cast<double>(points[i].y));
  }
  const Point2f box_center{static_cast<float>(0.5 * (min_x + max_x)),
                           static_cast<float>(0.5 * (min_y + max_y))};
  int i0 = -1;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    if (!Finite(points[i])) continue;
    const double d = Dist2(points[i], box_center);
    if (d < best) {
      best = d;
      i0 = i;
    }
  }
  if (i0 < 0) return;  // no finite point
  int i1 = -1;
  best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    if (!Finite(points[i])) continue;
    const double d = Dist2(points[i], points[i0]);
    if (d > kDuplicateDist2 && d < best) {
      best = d;
      i1 = i;
    }
  }
  if (i1 < 0) return;  // all points coincide
  int i2 = -1;
  best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    if (!Finite(points[i]) || Orient(points[i0], points[i1], points[i]) == 0.0) continue;
    // A near-duplicate of i0 or i1 would make a tiny, bogus circle.
    if (Dist2(points[i], points[i0]) <= kDuplicateDist2 ||
        Dist2(points[i], points[i1]) <= kDuplicateDist2) {
      continue;
    }
    const double r2 = Circumradius2(points[i0], points[i1], points[i]);
    if (r2 < best) {
      best = r2;
      i2 = i;
    }
  }
  if (i2 < 0) return;  // all points collinear
  if (Orient(points[i0], points[i1], points[i2]) < 0.0) std::swap(i1, i2);

  double cx = 0.0;
  double cy = 0.0;
  Circumcenter(points[i0], points[i1], points[i2], cx, cy);

  // Insertion order: distance from the centre; ties broken by coordinates so
  // exact duplicates end up adjacent, then by index for determinism.
  // Non-finite points sort last (and are skipped) without breaking the
  // ordering, which NaN keys would.
  const std::size_t count = static_cast<std::size_t>(n);
  ids_.resize(count);
  dists_.resize(count);
  for (int i = 0; i < n; ++i) {
    ids_[i] = i;
    const double dx = points[i].x - cx;
    const double dy = points[i].y - cy;
    dists_[i] = Finite(points[i]) ? dx * dx + dy * dy : std::numeric_limits<double>::infinity();
  }
  std::sort(ids_.begin(), ids_.end(), [&](int a, int b) {
    if (dists_[a] != dists_[b]) return dists_[a] < dists_[b];
    if (!Finite(points[a]) || !Finite(points[b])) return a < b;
    if (points[a].x != points[b].x) return points[a].x < points[b].x;
    if (points[a].y != points[b].y) return points[a].y < points[b].y;
    return a < b;
  });

  // At most 2n - 5 triangles.
  triangles_.reserve(6 * count);
  halfedges_.reserve(6 * count);
  hull_prev_.resize(count);
  hull_next_.resize(count);
  hull_tri_.resize(count);
  const int hash_size = hash_size_for(n);
  hull_hash_.assign(static_cast<std::size_t>(hash_size), -1);

  Sweep s{points,     triangles_,  halfedges_, hull_prev_, hull_next_, hull_tri_,
          hull_hash_, edge_stack_, cx,         cy,         hash_size,  n + 3};

  hull_next_[i0] = i1;
  hull_prev_[i2] = i1;
  hull_next_[i1] = i2;
  hull_prev_[i0] = i2;
  hull_next_[i2] = i0;
  hull_prev_[i1] = i0;
  hull_tri_[i0] = 0;
  hull_tri_[i1] = 1;
  hull_tri_[i2] = 2;
  hull_hash_[s.HashKey(points[i0])] = i0;
  hull_hash_[s.HashKey(points[i1])] = i1;
  hull_hash_[s.HashKey(points[i2])] = i2;
  s.AddTriangle(i0, i1, i2, -1, -1, -1);

  int last = -1;  // last inserted point, for the duplicate check
  for (int k = 0; k < n; ++k) {
    const int i = ids_[k];
    if (i == i0 || i == i1 || i == i2) continue;
    const Point2f& p = points[i];
    if (!Finite(p)) continue;
    if (last >= 0 && Dist2(p, points[last]) <= kDuplicateDist2) continue;
    if (Dist2(p, points[i0]) <= kDuplicateDist2 || Dist2(p, points[i1]) <= kDuplicateDist2 ||
        Dist2(p, points[i2]) <= kDuplicateDist2) {
      continue;
    }

    // A live hull vertex near p's angle, then the first edge p sees from
    // just before it.
    const int key = s.HashKey(p);
    int start = -1;
    for (int j = 0; j < hash_size; ++j) {
      const int v = hull_hash_[(key + j) % hash_size];
      if (v != -1 && hull_next_[v] != v) {
        start = v;
        break;
      }
    }
    if (start < 0) continue;  // unreachable: the hull is never empty
    start = hull_prev_[start];
    int e = start;
    int q = hull_next_[e];
    while (!(Orient(points[e], points[q], p) < 0.0)) {
      e = q;
      q = hull_next_[e];
      if (e == start) {
        e = -1;
        break;
      }
    }
    // No visible edge: p is on the hull (only near-duplicates get here).
    if (e < 0) continue;
    if (Dist2(p, points[e]) <= kDuplicateDist2 || Dist2(p, points[q]) <= kDuplicateDist2) continue;

    // Triangle on the first visible edge e -> q.
    int t = s.AddTriangle(e, i, q, -1, -1, hull_tri_[e]);
    hull_tri_[e] = t;
    hull_tri_[i] = t + 1;
    s.Legalize(t + 2);

    // Walk forward over further visible edges, removing hull vertices.
    int nv = q;
    while (true) {
      const int nq = hull_next_[nv];
      if (nq == e || !(Orient(points[nv], points[nq], p) < 0.0)) break;
      t = s.AddTriangle(nv, i, nq, hull_tri_[i], -1, hull_tri_[nv]);
      hull_tri_[i] = t + 1;
      s.Legalize(t + 2);
      hull_next_[nv] = nv;  // removed
      nv = nq;
    }
    // And backward.
    while (true) {
      const int pq = hull_prev_[e];
      if (pq == nv || !(Orient(points[pq], points[e], p) < 0.0)) break;
      t = s.AddTriangle(pq, i, e, -1, hull_tri_[e], hull_tri_[pq]);
      hull_tri_[pq] = t;
      s.Legalize(t + 2);
      hull_next_[e] = e;  // removed
      e = pq;
    }

    hull_prev_[i] = e;
    hull_next_[i] = nv;
    hull_prev_[nv] = i;
    hull_next_[e] = i;
    hull_hash_[s.HashKey(p)] = i;
    hull_hash_[s.HashKey(points[e])] = e;
    last = i;
  }
}

}  // namespace kg
