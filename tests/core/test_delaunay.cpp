#include "core/keygraphs/delaunay.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "core/support/rng.h"

namespace kg {
namespace {

using Points = std::vector<Point2f>;

double Orient(const Point2f& a, const Point2f& b, const Point2f& c) {
  return (static_cast<double>(b.x) - a.x) * (static_cast<double>(c.y) - a.y) -
         (static_cast<double>(b.y) - a.y) * (static_cast<double>(c.x) - a.x);
}

// True when d is strictly inside the circumcircle of the counter-clockwise
// (orient > 0) triangle abc, beyond a small tolerance relative to the
// magnitude of the determinant's terms. double suffices: the differences of
// float coordinates are exact in it, and its rounding (1e-16 relative) is
// far below the 1e-9 tolerance. (long double is software-emulated quad
// precision on AArch64: 20 times slower under QEMU.)
bool StrictlyInCircle(const Point2f& a, const Point2f& b, const Point2f& c, const Point2f& d) {
  using L = double;
  const L adx = static_cast<L>(a.x) - d.x, ady = static_cast<L>(a.y) - d.y;
  const L bdx = static_cast<L>(b.x) - d.x, bdy = static_cast<L>(b.y) - d.y;
  const L cdx = static_cast<L>(c.x) - d.x, cdy = static_cast<L>(c.y) - d.y;
  const L al = adx * adx + ady * ady;
  const L bl = bdx * bdx + bdy * bdy;
  const L cl = cdx * cdx + cdy * cdy;
  const L det =
      al * (bdx * cdy - cdx * bdy) + bl * (cdx * ady - adx * cdy) + cl * (adx * bdy - bdx * ady);
  const L perm = al * (std::fabs(bdx * cdy) + std::fabs(cdx * bdy)) +
                 bl * (std::fabs(cdx * ady) + std::fabs(adx * cdy)) +
                 cl * (std::fabs(adx * bdy) + std::fabs(bdx * ady));
  return det > 1e-9 * perm;
}

std::pair<float, float> Key(const Point2f& p) {
  return {p.x, p.y};
}

// Index of the first occurrence of each distinct point.
std::vector<int> FirstOccurrences(const Points& pts) {
  std::map<std::pair<float, float>, int> seen;
  std::vector<int> firsts;
  for (int i = 0; i < static_cast<int>(pts.size()); ++i) {
    if (seen.emplace(Key(pts[i]), i).second) firsts.push_back(i);
  }
  return firsts;
}

// Strict convex hull (no collinear vertices) by Andrew's monotone chain.
Points ConvexHull(Points p) {
  std::sort(p.begin(), p.end(), [](const Point2f& a, const Point2f& b) { return Key(a) < Key(b); });
  p.erase(std::unique(p.begin(), p.end(),
                      [](const Point2f& a, const Point2f& b) { return Key(a) == Key(b); }),
          p.end());
  if (p.size() < 3) return p;
  Points h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && Orient(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && Orient(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}

double PolygonArea(const Points& poly) {
  double a = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Point2f& p = poly[i];
    const Point2f& q = poly[(i + 1) % poly.size()];
    a += static_cast<double>(p.x) * q.y - static_cast<double>(q.x) * p.y;
  }
  return 0.5 * a;
}

// Distinct points lying on the hull boundary (vertices and points on edges).
int BoundaryPointCount(const Points& hull, const Points& pts) {
  int count = 0;
  for (int i : FirstOccurrences(pts)) {
    const Point2f& p = pts[i];
    for (std::size_t k = 0; k < hull.size(); ++k) {
      const Point2f& a = hull[k];
      const Point2f& b = hull[(k + 1) % hull.size()];
      if (Orient(a, b, p) == 0 && p.x >= std::min(a.x, b.x) && p.x <= std::max(a.x, b.x) &&
          p.y >= std::min(a.y, b.y) && p.y <= std::max(a.y, b.y)) {
        ++count;
        break;
      }
    }
  }
  return count;
}

// Structural checks that hold for any input with at least three non-collinear
// points: orientation, half-edge symmetry, every distinct point used exactly
// once, Euler's relation and area coverage of the convex hull.
void CheckTriangulation(const Points& pts, const Delaunay& d) {
  const auto& tri = d.triangles();
  const auto& he = d.halfedges();
  const int n = static_cast<int>(pts.size());
  ASSERT_EQ(tri.size() % 3, 0u);
  ASSERT_EQ(tri.size(), he.size());
  ASSERT_EQ(d.triangle_count(), static_cast<int>(tri.size() / 3));
  for (int v : tri) ASSERT_TRUE(v >= 0 && v < n) << v;

  double area = 0;
  for (int t = 0; t < d.triangle_count(); ++t) {
    const Point2f& a = pts[tri[3 * t]];
    const Point2f& b = pts[tri[3 * t + 1]];
    const Point2f& c = pts[tri[3 * t + 2]];
    const double o = Orient(a, b, c);
    ASSERT_GT(o, 0.0) << "triangle " << t;
    area += 0.5 * o;
  }

  int boundary_edges = 0;
  for (int e = 0; e < static_cast<int>(he.size()); ++e) {
    const int o = he[e];
    if (o == -1) {
      ++boundary_edges;
      continue;
    }
    ASSERT_TRUE(o >= 0 && o < static_cast<int>(he.size())) << e;
    ASSERT_NE(o / 3, e / 3) << e;
    ASSERT_EQ(he[o], e) << e;
    EXPECT_EQ(tri[e], tri[Delaunay::next(o)]) << e;
    EXPECT_EQ(tri[Delaunay::next(e)], tri[o]) << e;
  }

  // Each distinct point appears in the triangulation through exactly one of
  // its indices.
  std::vector<int> used(n, 0);
  for (int v : tri) used[v] = 1;
  std::map<std::pair<float, float>, int> uses;
  for (int i = 0; i < n; ++i) uses[Key(pts[i])] += used[i];
  for (const auto& [p, u] : uses) {
    EXPECT_EQ(u, 1) << "point (" << p.first << ", " << p.second << ")";
  }

  const Points hull = ConvexHull(pts);
  const int distinct = static_cast<int>(uses.size());
  const int h = BoundaryPointCount(hull, pts);
  EXPECT_EQ(d.triangle_count(), 2 * distinct - 2 - h);
  EXPECT_EQ(boundary_edges, h);
  const double hull_area = PolygonArea(hull);
  EXPECT_NEAR(area, hull_area, 1e-9 * hull_area);
}

// No input point strictly inside any triangle's circumcircle (brute force).
void CheckEmptyCircumcircles(const Points& pts, const Delaunay& d) {
  const auto& tri = d.triangles();
  int violations = 0;
  for (int t = 0; t < d.triangle_count(); ++t) {
    const Point2f& a = pts[tri[3 * t]];
    const Point2f& b = pts[tri[3 * t + 1]];
    const Point2f& c = pts[tri[3 * t + 2]];
    for (const Point2f& p : pts) {
      if (StrictlyInCircle(a, b, c, p)) ++violations;
    }
  }
  EXPECT_EQ(violations, 0);
}

// Local Delaunay property on every internal edge (implies the global one).
void CheckLocallyDelaunay(const Points& pts, const Delaunay& d) {
  const auto& tri = d.triangles();
  const auto& he = d.halfedges();
  int violations = 0;
  for (int e = 0; e < static_cast<int>(he.size()); ++e) {
    if (he[e] == -1) continue;
    const int t = e / 3;
    const Point2f& apex = pts[tri[Delaunay::prev(he[e])]];
    if (StrictlyInCircle(pts[tri[3 * t]], pts[tri[3 * t + 1]], pts[tri[3 * t + 2]], apex)) {
      ++violations;
    }
  }
  EXPECT_EQ(violations, 0);
}

Points Uniform(std::uint64_t seed, int n, double size = 2000.0) {
  Rng rng(seed);
  Points p(n);
  for (Point2f& q : p) {
    q.x = static_cast<float>(rng.uniform01() * size);
    q.y = static_cast<float>(rng.uniform01() * size);
  }
  return p;
}

// Gaussian blobs of very different spreads, as keypoints on textured patches.
Points Clustered(std::uint64_t seed, int n) {
  Rng rng(seed);
  const int clusters = 1 + n / 50;
  std::vector<Point2f> centers(clusters);
  std::vector<double> sigma(clusters);
  for (int c = 0; c < clusters; ++c) {
    centers[c] = {static_cast<float>(100 + rng.uniform01() * 1800),
                  static_cast<float>(100 + rng.uniform01() * 1800)};
    sigma[c] = 0.5 + 40.0 * rng.uniform01();
  }
  Points p(n);
  for (Point2f& q : p) {
    const int c = static_cast<int>(rng.uniform(static_cast<std::uint32_t>(clusters)));
    const double r = std::sqrt(-2.0 * std::log(1.0 - rng.uniform01())) * sigma[c];
    const double phi = 6.283185307179586 * rng.uniform01();
    q.x = static_cast<float>(std::clamp(centers[c].x + r * std::cos(phi), 0.0, 2000.0));
    q.y = static_cast<float>(std::clamp(centers[c].y + r * std::sin(phi), 0.0, 2000.0));
  }
  return p;
}

Points Grid(int rows, int cols, float x0, float y0, float step) {
  Points p;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      p.push_back({x0 + step * static_cast<float>(c), y0 + step * static_cast<float>(r)});
    }
  }
  return p;
}

void Shuffle(Points& p, std::uint64_t seed) {
  Rng rng(seed);
  for (std::size_t i = p.size(); i > 1; --i) {
    std::swap(p[i - 1], p[rng.uniform(static_cast<std::uint32_t>(i))]);
  }
}

Delaunay Triangulate(const Points& pts) {
  Delaunay d;
  d.triangulate(pts.data(), static_cast<int>(pts.size()));
  return d;
}

TEST(Delaunay, UniformRandomSets) {
  for (int n : {10, 100, 2000}) {
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      SCOPED_TRACE(testing::Message() << "n=" << n << " seed=" << seed);
      const Points pts = Uniform(seed * 7919 + static_cast<std::uint64_t>(n), n);
      const Delaunay d = Triangulate(pts);
      CheckTriangulation(pts, d);
      CheckEmptyCircumcircles(pts, d);
    }
  }
}

TEST(Delaunay, ClusteredRandomSets) {
  for (int n : {10, 100, 2000}) {
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      SCOPED_TRACE(testing::Message() << "n=" << n << " seed=" << seed);
      const Points pts = Clustered(seed * 104729 + static_cast<std::uint64_t>(n), n);
      const Delaunay d = Triangulate(pts);
      CheckTriangulation(pts, d);
      CheckEmptyCircumcircles(pts, d);
    }
  }
}

TEST(Delaunay, SmallCoordinateRange) {
  // Unit-square coordinates: nothing depends on the image scale.
  const Points pts = Uniform(99, 500, 1.0);
  const Delaunay d = Triangulate(pts);
  CheckTriangulation(pts, d);
  CheckEmptyCircumcircles(pts, d);
}

TEST(Delaunay, LargeSetIsValid) {
  const Points pts = Uniform(2024, 100000);
  const Delaunay d = Triangulate(pts);
  CheckTriangulation(pts, d);
  CheckLocallyDelaunay(pts, d);
}

TEST(Delaunay, FewerThanThreePoints) {
  Delaunay d;
  d.triangulate(nullptr, 0);
  EXPECT_EQ(d.triangle_count(), 0);
  const Points pts = {{1, 2}, {5, 7}};
  for (int n = 0; n <= 2; ++n) {
    d.triangulate(pts.data(), n);
    EXPECT_EQ(d.triangle_count(), 0) << n;
    EXPECT_TRUE(d.halfedges().empty());
  }
}

TEST(Delaunay, SingleTriangleIsPositivelyOriented) {
  for (const Points& pts : {Points{{0, 0}, {10, 0}, {0, 10}}, Points{{0, 0}, {0, 10}, {10, 0}},
                            Points{{3.5f, 1.25f}, {1999.f, 7.f}, {800.f, 1500.5f}}}) {
    const Delaunay d = Triangulate(pts);
    ASSERT_EQ(d.triangle_count(), 1);
    CheckTriangulation(pts, d);
    EXPECT_EQ(std::vector<int>(d.halfedges().begin(), d.halfedges().end()),
              (std::vector<int>{-1, -1, -1}));
  }
}

TEST(Delaunay, CollinearGivesNoTriangles) {
  Points horizontal, diagonal, vertical;
  for (int i = 0; i < 50; ++i) {
    horizontal.push_back({static_cast<float>(i * 3), 10.f});
    diagonal.push_back({static_cast<float>(7 * i + 1), static_cast<float>(5 * i + 2)});
    vertical.push_back({4.f, static_cast<float>((i * 37) % 50)});  // unsorted
  }
  Points with_duplicates = diagonal;
  with_duplicates.insert(with_duplicates.end(), diagonal.begin(), diagonal.begin() + 10);
  Shuffle(with_duplicates, 5);
  for (const Points& pts : {horizontal, diagonal, vertical, with_duplicates}) {
    Delaunay d = Triangulate(pts);
    EXPECT_EQ(d.triangle_count(), 0);
    EXPECT_TRUE(d.halfedges().empty());
  }
}

TEST(Delaunay, AllPointsIdenticalGivesNoTriangles) {
  const Points pts(20, Point2f{12.5f, 40.f});
  EXPECT_EQ(Triangulate(pts).triangle_count(), 0);
  const Points two_distinct = {{1, 1}, {1, 1}, {2, 3}, {2, 3}, {1, 1}};
  EXPECT_EQ(Triangulate(two_distinct).triangle_count(), 0);
}

TEST(Delaunay, DuplicatesAreIgnored) {
  const Points base = Uniform(17, 300);
  Points pts = base;
  Rng rng(3);
  for (int k = 0; k < 120; ++k) pts.push_back(base[rng.uniform(static_cast<std::uint32_t>(80))]);
  Shuffle(pts, 11);
  const Delaunay d = Triangulate(pts);
  const Delaunay ref = Triangulate(base);
  EXPECT_EQ(d.triangle_count(), ref.triangle_count());
  CheckTriangulation(pts, d);  // includes: each distinct point used once
  CheckEmptyCircumcircles(pts, d);
}

TEST(Delaunay, NearDuplicatesAreIgnored) {
  Points pts = {{0.f, 0.f}, {5e-10f, -3e-10f}, {1.f, 0.f}, {0.f, 1.f}, {1.f, 1.f}, {0.5f, 2.f}};
  const Delaunay d = Triangulate(pts);
  const auto& tri = d.triangles();
  const bool used0 = std::count(tri.begin(), tri.end(), 0) > 0;
  const bool used1 = std::count(tri.begin(), tri.end(), 1) > 0;
  EXPECT_NE(used0, used1);
  // The remaining 5 distinct points: a convex pentagon -> 3 triangles.
  EXPECT_EQ(d.triangle_count(), 3);
  for (int t = 0; t < d.triangle_count(); ++t) {
    EXPECT_GT(Orient(pts[tri[3 * t]], pts[tri[3 * t + 1]], pts[tri[3 * t + 2]]), 0.0);
  }
}

TEST(Delaunay, NonFinitePointsAreIgnored) {
  const Points base = Uniform(31, 200);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  Points pts = base;
  const std::vector<int> bad = {0, 50, 120, 203};  // 203: appended last
  pts.insert(pts.begin() + bad[0], Point2f{nan, 10.f});
  pts.insert(pts.begin() + bad[1], Point2f{inf, -inf});
  pts.insert(pts.begin() + bad[2], Point2f{nan, nan});
  pts.insert(pts.begin() + bad[3], Point2f{5.f, -inf});
  const Delaunay d = Triangulate(pts);
  EXPECT_EQ(d.triangle_count(), Triangulate(base).triangle_count());
  const auto& tri = d.triangles();
  for (int b : bad) EXPECT_EQ(std::count(tri.begin(), tri.end(), b), 0) << b;
  std::set<int> used(tri.begin(), tri.end());
  EXPECT_EQ(used.size(), base.size());
  for (int t = 0; t < d.triangle_count(); ++t) {
    EXPECT_GT(Orient(pts[tri[3 * t]], pts[tri[3 * t + 1]], pts[tri[3 * t + 2]]), 0.0);
  }
  CheckLocallyDelaunay(pts, d);

  const Points only_bad = {{nan, 1.f}, {inf, 2.f}, {3.f, nan}};
  EXPECT_EQ(Triangulate(only_bad).triangle_count(), 0);
}

TEST(Delaunay, RegularGridIsFullyTriangulated) {
  struct Case {
    int rows, cols;
    float x0, y0, step;
  };
  for (const Case& c : {Case{2, 2, 0, 0, 1}, Case{5, 7, 0, 0, 1}, Case{20, 30, 100, 200, 10},
                        Case{16, 16, 3.5f, 7.25f, 0.5f}, Case{40, 25, 0, 0, 48}}) {
    for (bool shuffled : {false, true}) {
      SCOPED_TRACE(testing::Message() << c.rows << "x" << c.cols << " step " << c.step
                                      << (shuffled ? " shuffled" : ""));
      Points pts = Grid(c.rows, c.cols, c.x0, c.y0, c.step);
      if (shuffled) Shuffle(pts, static_cast<std::uint64_t>(c.rows * 100 + c.cols));
      const Delaunay d = Triangulate(pts);
      EXPECT_EQ(d.triangle_count(), 2 * (c.rows - 1) * (c.cols - 1));
      CheckTriangulation(pts, d);
      CheckEmptyCircumcircles(pts, d);
    }
  }
}

TEST(Delaunay, CocircularLatticePoints) {
  // The 20 integer points on the circle of radius 25 (exactly cocircular).
  Points ring;
  for (int x = -25; x <= 25; ++x) {
    for (int y = -25; y <= 25; ++y) {
      if (x * x + y * y == 625)
        ring.push_back({1000.f + static_cast<float>(x), 500.f + static_cast<float>(y)});
    }
  }
  ASSERT_EQ(ring.size(), 20u);
  Delaunay d = Triangulate(ring);
  EXPECT_EQ(d.triangle_count(), 18);
  CheckTriangulation(ring, d);
  CheckEmptyCircumcircles(ring, d);

  Points with_center = ring;
  with_center.push_back({1000.f, 500.f});
  d = Triangulate(with_center);
  EXPECT_EQ(d.triangle_count(), 20);
  CheckTriangulation(with_center, d);
  CheckEmptyCircumcircles(with_center, d);
}

TEST(Delaunay, CoarseLatticeWithManyDegeneracies) {
  // Random points on a small lattice: many duplicates, collinear runs and
  // cocircular quadruples at once.
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed=" << seed);
    Rng rng(seed);
    Points pts(600);
    for (Point2f& p : pts) {
      p = {0.25f * static_cast<float>(rng.uniform(41)),
           0.25f * static_cast<float>(rng.uniform(31))};
    }
    const Delaunay d = Triangulate(pts);
    CheckTriangulation(pts, d);
    CheckEmptyCircumcircles(pts, d);
  }
}

TEST(Delaunay, ReuseMatchesFreshObject) {
  const Points big = Clustered(5, 2000);
  const Points small = Uniform(6, 10);
  const Points line = {{0, 0}, {1, 1}, {2, 2}, {3, 3}};
  const Points grid = Grid(9, 11, 0, 0, 2);
  Delaunay reused;
  for (const Points* pts : {&big, &small, &line, &grid, &big, &small}) {
    reused.triangulate(pts->data(), static_cast<int>(pts->size()));
    const Delaunay fresh = Triangulate(*pts);
    EXPECT_EQ(reused.triangles(), fresh.triangles());
    EXPECT_EQ(reused.halfedges(), fresh.halfedges());
  }
  // Once capacity is reached the output buffers are not reallocated.
  reused.triangulate(big.data(), static_cast<int>(big.size()));
  const int* tri_data = reused.triangles().data();
  const int* he_data = reused.halfedges().data();
  reused.triangulate(small.data(), static_cast<int>(small.size()));
  reused.triangulate(big.data(), static_cast<int>(big.size()));
  EXPECT_EQ(reused.triangles().data(), tri_data);
  EXPECT_EQ(reused.halfedges().data(), he_data);
}

}  // namespace
}  // namespace kg
