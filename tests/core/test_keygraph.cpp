// Keygraph structures and keytuples (paper sections 4-5).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <set>
#include <vector>

#include "core/keygraphs/delaunay.h"
#include "core/keygraphs/keygraph.h"
#include "core/support/rng.h"

namespace kg {
namespace {

using Perm = std::vector<int>;

// All bijections iota: {0..k-1} -> {0..k-1} that preserve arcs both ways.
std::set<Perm> isomorphisms_brute_force(int k, const std::vector<std::pair<int, int>>& gm,
                                        const std::vector<std::pair<int, int>>& gs) {
  std::set<Perm> out;
  Perm iota(k);
  for (int i = 0; i < k; ++i) iota[i] = i;
  auto has = [](const std::vector<std::pair<int, int>>& g, int a, int b) {
    return std::find(g.begin(), g.end(), std::make_pair(a, b)) != g.end();
  };
  do {
    bool ok = true;
    for (int a = 0; a < k && ok; ++a) {
      for (int b = 0; b < k && ok; ++b) {
        if (a != b) ok = has(gm, a, b) == has(gs, iota[a], iota[b]);
      }
    }
    if (ok) out.insert(iota);
  } while (std::next_permutation(iota.begin(), iota.end()));
  return out;
}

// Keytuples of a graph with respect to sigma: every ordering that satisfies it.
std::vector<Perm> keytuples(int k, const std::vector<std::pair<int, int>>& g,
                            const std::uint8_t* sigma) {
  std::vector<int> from, to;
  for (auto [a, b] : g) {
    from.push_back(a);
    to.push_back(b);
  }
  std::vector<Perm> out;
  Perm order(k);
  for (int i = 0; i < k; ++i) order[i] = i;
  do {
    if (is_keytuple(order.data(), k, sigma, from.data(), to.data(), static_cast<int>(from.size())))
      out.push_back(order);
  } while (std::next_permutation(order.begin(), order.end()));
  return out;
}

// Isomorphisms through keytuples (paper's procedure): one scene keytuple w,
// and for each model keytuple v the bijection v_i -> w_i.
std::set<Perm> isomorphisms_by_keytuples(int k, const std::vector<std::pair<int, int>>& gm,
                                         const std::vector<std::pair<int, int>>& gs,
                                         const std::uint8_t* sigma, std::size_t scene_choice) {
  std::set<Perm> out;
  const std::vector<Perm> scene = keytuples(k, gs, sigma);
  if (scene.empty()) return out;
  const Perm& w = scene[scene_choice % scene.size()];
  for (const Perm& v : keytuples(k, gm, sigma)) {
    Perm iota(k);
    for (int i = 0; i < k; ++i) iota[v[i]] = w[i];
    out.insert(iota);
  }
  return out;
}

std::vector<std::pair<int, int>> arcs_of(int k, const std::uint8_t* sigma, const Perm& order) {
  std::vector<std::pair<int, int>> g;
  for (int i = 0; i < k; ++i) {
    for (int j = 0; j < k; ++j) {
      if (sigma[i * k + j]) g.emplace_back(order[i], order[j]);
    }
  }
  return g;
}

TEST(Keytuple, MatricesAreThePapers) {
  std::uint8_t s2[4], s3[9], s4[16];
  keytuple_matrix(Structure::kArc, s2);
  keytuple_matrix(Structure::kCircuit3, s3);
  keytuple_matrix(Structure::kCircuit4, s4);
  EXPECT_EQ(std::vector<int>(s2, s2 + 4), (std::vector<int>{0, 1, 0, 0}));
  EXPECT_EQ(std::vector<int>(s3, s3 + 9), (std::vector<int>{0, 1, 0, 0, 0, 1, 1, 0, 0}));
  EXPECT_EQ(std::vector<int>(s4, s4 + 16),
            (std::vector<int>{0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 1, 0, 0, 0}));
}

TEST(Keytuple, CircuitKeytuplesAreTheCyclicRotations) {
  std::uint8_t sigma[16];
  for (Structure s : {Structure::kCircuit3, Structure::kCircuit4}) {
    const int k = vertex_count(s);
    keytuple_matrix(s, sigma);
    Perm identity(k);
    for (int i = 0; i < k; ++i) identity[i] = i;
    const std::vector<Perm> tuples = keytuples(k, arcs_of(k, sigma, identity), sigma);
    ASSERT_EQ(static_cast<int>(tuples.size()), k);
    for (const Perm& t : tuples) {
      for (int i = 0; i < k; ++i) EXPECT_EQ(t[(i + 1) % k], (t[i] + 1) % k);
    }
  }
}

// The proposition of section 4 for the paper's structures, every relabelling
// of the scene graph and every choice of scene keytuple.
TEST(Keytuple, PropositionHoldsForThePapersStructures) {
  std::uint8_t sigma[16];
  for (Structure s : {Structure::kArc, Structure::kCircuit3, Structure::kCircuit4}) {
    const int k = vertex_count(s);
    keytuple_matrix(s, sigma);
    Perm identity(k), relabel(k);
    for (int i = 0; i < k; ++i) identity[i] = relabel[i] = i;
    const auto gm = arcs_of(k, sigma, identity);
    do {
      const auto gs = arcs_of(k, sigma, relabel);
      const std::set<Perm> brute = isomorphisms_brute_force(k, gm, gs);
      ASSERT_FALSE(brute.empty());
      for (std::size_t choice = 0; choice < 4; ++choice)
        EXPECT_EQ(isomorphisms_by_keytuples(k, gm, gs, sigma, choice), brute);
    } while (std::next_permutation(relabel.begin(), relabel.end()));
  }
}

// The proposition holds for any sigma: random digraphs on k vertices, sigma
// the adjacency of a random ordering of the scene graph.
TEST(Keytuple, PropositionHoldsForRandomDigraphs) {
  Rng rng(7);
  for (int trial = 0; trial < 300; ++trial) {
    const int k = 2 + static_cast<int>(rng.uniform(4));  // 2..5 vertices
    std::vector<std::pair<int, int>> gm;
    for (int a = 0; a < k; ++a) {
      for (int b = 0; b < k; ++b) {
        if (a != b && rng.uniform(2) == 1) gm.emplace_back(a, b);
      }
    }
    Perm relabel(k);
    for (int i = 0; i < k; ++i) relabel[i] = i;
    for (int i = k - 1; i > 0; --i)
      std::swap(relabel[i], relabel[rng.uniform(static_cast<std::uint32_t>(i + 1))]);
    std::vector<std::pair<int, int>> gs;
    for (auto [a, b] : gm) gs.emplace_back(relabel[a], relabel[b]);
    // sigma from a random ordering of the scene graph.
    Perm order(k);
    for (int i = 0; i < k; ++i) order[i] = i;
    for (int i = k - 1; i > 0; --i)
      std::swap(order[i], order[rng.uniform(static_cast<std::uint32_t>(i + 1))]);
    std::vector<std::uint8_t> sigma(static_cast<std::size_t>(k * k), 0);
    for (int i = 0; i < k; ++i) {
      for (int j = 0; j < k; ++j) {
        sigma[i * k + j] =
            std::find(gs.begin(), gs.end(), std::make_pair(order[i], order[j])) != gs.end();
      }
    }
    const std::set<Perm> brute = isomorphisms_brute_force(k, gm, gs);
    EXPECT_EQ(isomorphisms_by_keytuples(k, gm, gs, sigma.data(), trial), brute)
        << "trial " << trial;
    // A non-isomorphic scene graph (one arc added or removed) has none.
    auto other = gs;
    if (!other.empty()) {
      other.pop_back();
      EXPECT_TRUE(isomorphisms_brute_force(k, gm, other).empty());
      EXPECT_TRUE(isomorphisms_by_keytuples(k, gm, other, sigma.data(), trial).empty());
    }
  }
}

TEST(Geometry, ClockwiseOnScreen) {
  // y grows downwards: right, then down is a clockwise turn on screen.
  const Point2f tri[3] = {{0, 0}, {10, 0}, {10, 10}};
  EXPECT_GT(orient(tri[0], tri[1], tri[2]), 0.f);
  EXPECT_TRUE(is_clockwise_circuit(tri, 3));
  const Point2f mirrored[3] = {{0, 0}, {10, 0}, {10, -10}};
  EXPECT_FALSE(is_clockwise_circuit(mirrored, 3));
  const Point2f square[4] = {{0, 0}, {10, 0}, {10, 10}, {0, 10}};
  EXPECT_TRUE(is_clockwise_circuit(square, 4));
  const Point2f dart[4] = {{0, 0}, {10, 0}, {3, 3}, {0, 10}};  // not convex
  EXPECT_FALSE(is_clockwise_circuit(dart, 4));
}

std::vector<Point2f> random_points(Rng& rng, int n, float size) {
  std::vector<Point2f> p;
  for (int i = 0; i < n; ++i)
    p.push_back(
        {static_cast<float>(rng.uniform01() * size), static_cast<float>(rng.uniform01() * size)});
  return p;
}

TEST(SceneKeygraphs, FromDelaunayEdgesFacesAndInternalEdges) {
  Rng rng(11);
  const std::vector<Point2f> pts = random_points(rng, 300, 500.f);
  Delaunay dt;
  dt.triangulate(pts.data(), static_cast<int>(pts.size()));
  const auto& tri = dt.triangles();
  const auto& half = dt.halfedges();
  WorkVector<SceneKeygraph> g;

  scene_keygraphs(dt, pts.data(), Structure::kArc, g);
  int undirected = 0;
  for (std::size_t e = 0; e < half.size(); ++e)
    undirected += (half[e] < 0 || static_cast<int>(e) < half[e]);
  EXPECT_EQ(static_cast<int>(g.size()), undirected);
  // Both vertices of an arc keygraph are origins of real half-edges: the arc
  // goes from the origin of edges[0] to the origin of edges[1].
  for (const SceneKeygraph& s : g) {
    ASSERT_GE(s.edges[1], 0);
    EXPECT_EQ(s.edges[1], Delaunay::next(s.edges[0]));
    EXPECT_NE(tri[s.edges[0]], tri[s.edges[1]]);
  }

  scene_keygraphs(dt, pts.data(), Structure::kCircuit3, g);
  ASSERT_EQ(static_cast<int>(g.size()), dt.triangle_count());
  for (const SceneKeygraph& s : g) {
    const Point2f v[3] = {pts[tri[s.edges[0]]], pts[tri[s.edges[1]]], pts[tri[s.edges[2]]]};
    EXPECT_TRUE(is_clockwise_circuit(v, 3));
    // Each arc (v_i, v_i+1) is the half-edge named for it.
    for (int i = 0; i < 3; ++i)
      EXPECT_EQ(tri[Delaunay::next(s.edges[i])], tri[s.edges[(i + 1) % 3]]);
  }

  scene_keygraphs(dt, pts.data(), Structure::kCircuit4, g);
  int internal = 0;
  for (std::size_t e = 0; e < half.size(); ++e)
    internal += (half[e] >= 0 && static_cast<int>(e) < half[e]);
  EXPECT_GT(static_cast<int>(g.size()), internal / 2);  // most quadrilaterals are convex
  EXPECT_LE(static_cast<int>(g.size()), internal);
  for (const SceneKeygraph& s : g) {
    Point2f v[4];
    std::set<int> distinct;
    for (int i = 0; i < 4; ++i) {
      v[i] = pts[tri[s.edges[i]]];
      distinct.insert(tri[s.edges[i]]);
      EXPECT_EQ(tri[Delaunay::next(s.edges[i])], tri[s.edges[(i + 1) % 4]]);
    }
    EXPECT_EQ(distinct.size(), 4u);
    EXPECT_TRUE(is_clockwise_circuit(v, 4));
  }
}

TEST(ModelKeygraphs, CountMatchesBruteForce) {
  Rng rng(5);
  const std::vector<Point2f> p = random_points(rng, 60, 150.f);
  const int n = static_cast<int>(p.size());
  for (Structure s : {Structure::kArc, Structure::kCircuit3, Structure::kCircuit4}) {
    GraphParams gp;
    gp.structure = s;
    gp.min_distance = 10.f;
    gp.max_distance = 60.f;
    std::vector<std::uint32_t> offsets(n + 1, 0), to;
    for (int a = 0; a < n; ++a) {
      offsets[a] = static_cast<std::uint32_t>(to.size());
      for (int b = 0; b < n; ++b) {
        if (a != b && is_model_arc(p[a], p[b], gp)) to.push_back(static_cast<std::uint32_t>(b));
      }
    }
    offsets[n] = static_cast<std::uint32_t>(to.size());
    // Brute force over ordered tuples, divided by the k rotations.
    std::uint64_t brute = 0;
    const int k = vertex_count(s);
    for (int a = 0; a < n; ++a) {
      for (int b = 0; b < n; ++b) {
        if (b == a || !is_model_arc(p[a], p[b], gp)) continue;
        if (k == 2) {
          ++brute;
          continue;
        }
        for (int c = 0; c < n; ++c) {
          if (c == a || c == b || !is_model_arc(p[b], p[c], gp)) continue;
          if (k == 3) {
            const Point2f t[3] = {p[a], p[b], p[c]};
            brute += is_model_arc(p[c], p[a], gp) && is_clockwise_circuit(t, 3);
            continue;
          }
          for (int d = 0; d < n; ++d) {
            if (d == a || d == b || d == c) continue;
            const Point2f q[4] = {p[a], p[b], p[c], p[d]};
            brute += is_model_arc(p[c], p[d], gp) && is_model_arc(p[d], p[a], gp) &&
                     is_clockwise_circuit(q, 4);
          }
        }
      }
    }
    if (k > 2) brute /= static_cast<std::uint64_t>(k);
    EXPECT_GT(brute, 0u);
    EXPECT_EQ(count_model_keygraphs(p.data(), n, offsets.data(), to.data(), gp), brute)
        << "structure " << k;
  }
}

TEST(SampleSize, TwoCircuitsOrFourKeypoints) {
  EXPECT_EQ(sample_size(Structure::kArc), 2);
  EXPECT_EQ(sample_size(Structure::kCircuit3), 2);
  EXPECT_EQ(sample_size(Structure::kCircuit4), 1);
}

}  // namespace
}  // namespace kg
