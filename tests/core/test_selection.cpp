// Keytuple selection (core/selection/selection.cpp) against a brute-force reading of
// its definition, on a real model and frame: for every scene 3-circuit
// (a, b, c), every model triple (a_m, b_m, c_m), clockwise, whose arcs
// a_m -> b_m, b_m -> c_m and c_m -> a_m are each among the model arcs the
// search finds for the corresponding scene arc (4-circuits alike). The
// selector reuses one direction's look-up for the other, cuts the lists by
// a semi-join on candidate flags and joins what is left; the reference
// searches every directed scene arc on its own and joins sets.
// With the float32 encoding and the exact search both directions of an arc
// find the same model arcs (reversing a profile is an isometry of
// descriptors), so the two must agree exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "builder/in_memory_index.h"
#include "builder/model_builder.h"
#include "core/description/arc_attributes.h"
#include "core/description/arc_descriptor.h"
#include "core/description/arc_types.h"
#include "core/image/blur.h"
#include "core/keygraphs/delaunay.h"
#include "core/keygraphs/keygraph.h"
#include "core/keypoints/hessian.h"
#include "core/sampling/sampling.h"
#include "core/selection/arc_adjacency.h"
#include "core/selection/selection.h"
#include "support/test_data.h"

namespace kg {
namespace {

using Match = std::array<std::int64_t, 8>;  // model vertices, scene vertices (4-circuits: 4 + 4)

struct Scene {
  cv::Mat gray;
  std::vector<Point2f> points;
  std::vector<float> scales;
  Delaunay triangulation;
  WorkVector<SceneKeygraph> keygraphs;
  Plane<std::uint8_t> blurred;
};

void prepare_scene(const cv::Mat& gray, const Params& params, const Limits& limits, Scene& s) {
  s.gray = gray;
  HessianDetector hessian;
  std::vector<Keypoint> keypoints;
  hessian.detect(ImageView(gray.data, gray.cols, gray.rows, static_cast<int>(gray.step)),
                 params.keypoints, limits.max_keypoints, keypoints);
  SeparatedSampler sampler;
  std::vector<int> selected;
  sampler.sample(keypoints.data(), static_cast<int>(keypoints.size()),
                 params.graph.scene_sample_distance, nullptr, selected);
  for (int i : selected) {
    const Keypoint& k = keypoints[static_cast<std::size_t>(i)];
    s.points.push_back({k.x, k.y});
    s.scales.push_back(k.scale);
  }
  s.triangulation.triangulate(s.points.data(), static_cast<int>(s.points.size()));
  scene_keygraphs(s.triangulation, s.points.data(), params.graph.structure, s.keygraphs);
  Plane<float> scratch;
  gaussian_blur(ImageView(gray.data, gray.cols, gray.rows, static_cast<int>(gray.step)),
                params.descriptor.blur_sigma, s.blurred, scratch);
}

// The box model, the box_in_scene frame and the brute-force reference set,
// built once for every test here.
struct Case {
  Params params;
  InMemoryIndex built;
  Scene scene;
  std::set<Match> expected;
};

void build_case(Case& c, Structure structure) {
  c.params.graph.structure = structure;
  c.params.descriptor.encoding = DescriptorEncoding::kFloat32;
  c.params.descriptor.max_search_leaves = 0;  // exact
  c.params.graph.max_anisotropy = 0.f;        // no local shape check: the bare definition
  const Params& params = c.params;
  BuiltModel model;
  ASSERT_TRUE(
      build_model(test::load_gray(test::opencv_data("box.png")), "box", params, model).is_ok());
  ASSERT_TRUE(c.built.build({model}, params).is_ok());
  const ModelIndex& index = c.built.index();
  const Limits limits;
  prepare_scene(test::load_gray(test::opencv_data("box_in_scene.png")), params, limits, c.scene);
  ASSERT_GT(c.scene.keygraphs.size(), 300u);

  // Reference: each directed scene arc searched on its own.
  const ArcSearch search(index);
  const WorkVector<int>& tri = c.scene.triangulation.triangles();
  std::vector<std::set<std::pair<std::uint32_t, std::uint32_t>>> similar(tri.size());
  std::vector<float> profile;
  std::vector<std::uint32_t> found(static_cast<std::size_t>(limits.max_arc_matches));
  for (std::size_t e = 0; e < tri.size(); ++e) {
    const int from = tri[e],
              to = tri[static_cast<std::size_t>(Delaunay::next(static_cast<int>(e)))];
    const Point2f a = c.scene.points[static_cast<std::size_t>(from)];
    const Point2f b = c.scene.points[static_cast<std::size_t>(to)];
    ArcDescriptor d;
    if (chebyshev(a, b) < params.graph.min_distance ||
        !arc_descriptor(view_of(c.scene.blurred), a, b, params.descriptor, profile, d))
      continue;
    float attributes[kArcAttributes];
    const bool scaled = arc_attributes(a, b, c.scene.scales[static_cast<std::size_t>(from)],
                                       c.scene.scales[static_cast<std::size_t>(to)], attributes);
    const std::uint32_t n = search.radius_search(d, scaled ? attributes : nullptr, found.data(),
                                                 static_cast<std::uint32_t>(found.size()));
    ASSERT_LE(n, found.size());
    for (std::uint32_t i = 0; i < n; ++i) {
      const ModelArc arc = index.arc(found[i]);
      similar[e].insert({arc.from, arc.to});
    }
  }
  const Point2f* model_points = index.keypoints();
  const int k = vertex_count(structure);
  for (const SceneKeygraph& g : c.scene.keygraphs) {
    Match scene{};
    for (int i = 0; i < k; ++i) scene[4 + i] = tri[static_cast<std::size_t>(g.edges[i])];
    const auto& ab = similar[static_cast<std::size_t>(g.edges[0])];
    if (k == 2) {  // an arc keygraph: every similar model arc
      for (const auto& [am, bm] : ab) {
        Match m = scene;
        m[0] = am, m[1] = bm;
        c.expected.insert(m);
      }
      continue;
    }
    const auto& bc = similar[static_cast<std::size_t>(g.edges[1])];
    const auto& cx = similar[static_cast<std::size_t>(g.edges[2])];
    for (const auto& [am, bm] : ab) {
      for (auto it = bc.lower_bound({bm, 0}); it != bc.end() && it->first == bm; ++it) {
        const std::uint32_t cm = it->second;
        if (cm == am) continue;
        if (k == 3) {
          if (cx.count({cm, am}) == 0) continue;
          if (!(orient(model_points[am], model_points[bm], model_points[cm]) > 0.f)) continue;
          Match m = scene;
          m[0] = am, m[1] = bm, m[2] = cm;
          c.expected.insert(m);
          continue;
        }
        const auto& da = similar[static_cast<std::size_t>(g.edges[3])];
        for (auto jt = cx.lower_bound({cm, 0}); jt != cx.end() && jt->first == cm; ++jt) {
          const std::uint32_t dm = jt->second;
          if (dm == am || dm == bm || da.count({dm, am}) == 0) continue;
          const Point2f q[4] = {model_points[am], model_points[bm], model_points[cm],
                                model_points[dm]};
          if (!is_clockwise_circuit(q, 4)) continue;
          Match m = scene;
          m[0] = am, m[1] = bm, m[2] = cm, m[3] = dm;
          c.expected.insert(m);
        }
      }
    }
  }
}

const Case& the_case(Structure structure = Structure::kCircuit3) {
  static Case cases[3];
  static bool built[3] = {false, false, false};
  const int i = vertex_count(structure) - 2;
  if (!built[i]) {
    build_case(cases[i], structure);
    built[i] = true;
  }
  return cases[i];
}

// The selector's correspondences as a set (each must be new). Checks the
// join's state after every keygraph; `kept_share`: the share of the
// model arcs its semi-join received that it kept.
// `leaves`: the search's leaf budget (-1: the index's); `adjacency`: set,
// circuits are completed from two lists (graph.complete_circuits).
std::set<Match> select_all(const Case& c, const Limits& limits, DetectStats& stats,
                           double* kept_share = nullptr, int leaves = -1,
                           const ArcAdjacency* adjacency = nullptr) {
  const ArcSearch search =
      leaves < 0 ? ArcSearch(c.built.index()) : ArcSearch(c.built.index(), leaves);
  Selector selector;
  selector.reserve(limits, c.built.index(), adjacency != nullptr);
  // The description stage, as the detector runs it before the selection.
  const cv::Mat& gray = c.scene.gray;
  SceneArcs arcs;
  arcs.reserve(gray.cols, gray.rows, static_cast<int>(c.scene.points.size()),
               c.params.descriptor.blur_sigma);
  arcs.blur(ImageView(gray.data, gray.cols, gray.rows, static_cast<int>(gray.step)),
            c.params.descriptor);
  const Structure structure = c.params.graph.structure;
  arcs.describe(search, c.params, c.scene.points.data(), c.scene.scales.data(),
                c.scene.triangulation, c.scene.keygraphs,
                structure == Structure::kArc ? 1 : vertex_count(structure));
  SelectionInput in;
  in.index = &c.built.index();
  in.params = &c.params;
  in.search = &search;
  in.scene_points = c.scene.points.data();
  in.triangulation = &c.scene.triangulation;
  in.keygraphs = &c.scene.keygraphs;
  in.arcs = &arcs;
  in.adjacency = adjacency;
  WorkVector<KeygraphMatch> matches;
  matches.reserve(static_cast<std::size_t>(limits.max_correspondences));
  // The join's state is clear after every keygraph: selected one keygraph
  // at a time (a flag left set would only cost time, so no output shows it).
  WorkVector<SceneKeygraph> one;
  one.reserve(1);
  SelectionInput single = in;
  single.keygraphs = &one;
  WorkVector<KeygraphMatch> scratch;
  scratch.reserve(static_cast<std::size_t>(limits.max_correspondences));
  int left_set = 0;
  for (const SceneKeygraph& g : c.scene.keygraphs) {
    one.assign(1, g);
    DetectStats ignored;
    selector.select(single, limits, scratch, ignored);
    left_set += selector.join_state_clear() ? 0 : 1;
  }
  EXPECT_EQ(left_set, 0) << "keygraphs that left a candidate flag or chain head set";
  selector.select(in, limits, matches, stats);
  EXPECT_TRUE(selector.join_state_clear()) << "a candidate flag left set after the frame";
  if (kept_share != nullptr)
    *kept_share = stats.join_arcs_in == 0 ? 1.0
                                          : static_cast<double>(stats.join_arcs_kept) /
                                                static_cast<double>(stats.join_arcs_in);
  std::set<Match> selected;
  for (const KeygraphMatch& m : matches) {
    EXPECT_EQ(m.model_id, c.built.index().model_of_keypoint(m.model_vertices[0]));
    Match key{};
    for (int i = 0; i < vertex_count(c.params.graph.structure); ++i) {
      key[i] = m.model_vertices[i];
      key[4 + i] = m.scene_vertices[i];
    }
    const bool fresh = selected.insert(key).second;
    EXPECT_TRUE(fresh) << "a correspondence selected twice";
  }
  return selected;
}

// Selects with `limits`, nothing cut, and requires exactly the brute-force
// set; `kept_share` as select_all().
void expect_brute_force_set(const Case& c, const Limits& limits, double* kept_share = nullptr) {
  DetectStats stats;
  const std::set<Match> selected = select_all(c, limits, stats, kept_share);
  ASSERT_FALSE(stats.truncated_arc_matches);
  ASSERT_FALSE(stats.truncated_correspondences);
  EXPECT_EQ(selected, c.expected);
  if (kept_share != nullptr)
    std::printf("semi-join kept %.2f %% of the model arcs it received\n", 100.0 * *kept_share);
}

TEST(Selection, EqualsBruteForceJoinOnRealImages) {
  const Case& c = the_case();
  // The frame holds the box: many correspondences (none: the case failed to build).
  ASSERT_GT(c.expected.size(), 50u);
  double kept = 1.0;
  expect_brute_force_set(c, Limits{}, &kept);
  // The semi-join does cut: a pass-through would give the same output.
  // With model views a keypoint has arcs from several views, so more of
  // them survive (measured 11.1 %; 2.7 % with the single model image).
  EXPECT_LT(kept, 0.20);
}

// Circuit completion (graph.complete_circuits): a circuit is also selected
// from two searched arcs when the model arc closing it is within the radius
// and box of the third scene arc, compared directly. With the exact search
// the third arc is among the searched ones whenever it matches, so the
// output is the brute-force set again, each circuit once although every
// pass of the three finds it: the completion's funnel (DetectStats) closes
// each exactly three times (the case checks no local map: every clockwise
// triple is plausible).
TEST(Selection, CompletedCircuitsWithExactSearchEqualBruteForceJoin) {
  const Case& c = the_case();
  ArcAdjacency adjacency(std::pmr::get_default_resource());
  adjacency.build(c.built.index(), true);
  DetectStats stats;
  const std::set<Match> selected = select_all(c, Limits{}, stats, nullptr, 0, &adjacency);
  ASSERT_FALSE(stats.truncated_arc_matches);
  ASSERT_FALSE(stats.truncated_correspondences);
  EXPECT_EQ(selected, c.expected);
  EXPECT_EQ(stats.completion_closed, 3 * static_cast<long long>(selected.size()));
  EXPECT_GT(stats.completion_tried, stats.completion_clockwise);
  EXPECT_EQ(stats.completion_clockwise, stats.completion_plausible);
  EXPECT_GT(stats.completion_plausible, stats.completion_closed);
  std::printf("completion: %lld triples joined, %lld clockwise, %lld plausible, %lld closed\n",
              stats.completion_tried, stats.completion_clockwise, stats.completion_plausible,
              stats.completion_closed);
}

// Two models (box.png twice): each correspondence names the model of its
// keypoints (the selector's table of keypoint owners, select_all() checks
// it against ModelIndex::model_of_keypoint), and both models are found.
TEST(Selection, NamesTheModelOfEachCorrespondence) {
  Case c;
  c.params.descriptor.encoding = DescriptorEncoding::kFloat32;
  BuiltModel box, copy;
  const cv::Mat gray = test::load_gray(test::opencv_data("box.png"));
  ASSERT_TRUE(build_model(gray, "box", c.params, box).is_ok());
  ASSERT_TRUE(build_model(gray, "box-copy", c.params, copy).is_ok());
  ASSERT_TRUE(c.built.build({box, copy}, c.params).is_ok());
  prepare_scene(test::load_gray(test::opencv_data("box_in_scene.png")), c.params, Limits{},
                c.scene);
  ArcAdjacency adjacency(std::pmr::get_default_resource());
  adjacency.build(c.built.index(), true);
  DetectStats stats;
  const std::set<Match> selected = select_all(c, Limits{}, stats, nullptr, -1, &adjacency);
  const std::uint32_t second = c.built.index().model(1).keypoint_begin;
  int in_second = 0;
  for (const Match& m : selected) in_second += m[0] >= second ? 1 : 0;
  const auto in_first = static_cast<int>(selected.size()) - in_second;
  std::printf("correspondences: %d of the first model, %d of its copy\n", in_first, in_second);
  EXPECT_GT(in_first, 20);
  EXPECT_GT(in_second, 20);
}

// With an approximate search of one leaf per query most arcs go unfound.
// Completion then selects every circuit the uncompleted join does, more
// besides, and only true ones: each completed circuit's three arcs are all
// similar by the exact search's reading (the brute-force set).
TEST(Selection, CompletedCircuitsRecoverArcsTheSearchBudgetMissed) {
  const Case& c = the_case();
  ArcAdjacency adjacency(std::pmr::get_default_resource());
  adjacency.build(c.built.index(), true);
  DetectStats plain_stats, completed_stats;
  const std::set<Match> plain = select_all(c, Limits{}, plain_stats, nullptr, 1);
  const std::set<Match> completed =
      select_all(c, Limits{}, completed_stats, nullptr, 1, &adjacency);
  ASSERT_FALSE(completed_stats.truncated_correspondences);
  // Without completion the funnel is empty.
  EXPECT_EQ(plain_stats.completion_tried, 0);
  EXPECT_EQ(plain_stats.completion_closed, 0);
  EXPECT_GE(completed_stats.completion_closed, static_cast<long long>(completed.size()));
  EXPECT_TRUE(std::includes(completed.begin(), completed.end(), plain.begin(), plain.end()))
      << "completion lost a circuit the three lists join";
  EXPECT_TRUE(
      std::includes(c.expected.begin(), c.expected.end(), completed.begin(), completed.end()))
      << "a completed circuit has an arc that is not similar";
  std::printf("one leaf: %zu circuits joined, %zu completed, %zu exact\n", plain.size(),
              completed.size(), c.expected.size());
  EXPECT_GT(completed.size(), plain.size() + plain.size() / 4)
      << "completion should recover a sizeable share of the circuits one leaf misses";
}

// The arc table: every model arc once, in the row of its source, rows
// sorted by target; find() answers a whole batch of look-ups at once with
// each pair's complete range, and an empty one for a pair without an arc.
TEST(ArcAdjacency, FindsEveryModelArcInItsSourcesRow) {
  const Case& c = the_case();
  const ModelIndex& index = c.built.index();
  ArcAdjacency adjacency(std::pmr::get_default_resource());
  adjacency.build(index, true);
  ASSERT_GT(index.arc_count(), 1000u);
  // How many arcs each keypoint pair has (views store a pair once per
  // distinct description): a range must hold all of them.
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::ptrdiff_t> arcs_of_pair;
  for (std::uint32_t slot = 0; slot < index.arc_count(); ++slot)
    ++arcs_of_pair[{index.arc(slot).from, index.arc(slot).to}];
  constexpr int kBatch = ArcAdjacency::kBatch;
  for (std::uint32_t first = 0; first < index.arc_count(); first += kBatch) {
    const int n = static_cast<int>(std::min<std::uint32_t>(kBatch, index.arc_count() - first));
    std::uint32_t from[kBatch], to[kBatch];
    for (int i = 0; i < n; ++i) {
      const ModelArc arc = index.arc(first + static_cast<std::uint32_t>(i));
      from[i] = arc.from;
      to[i] = arc.to;
    }
    const std::uint64_t* begin[kBatch];
    const std::uint64_t* end[kBatch];
    adjacency.find(from, to, n, begin, end);
    for (int i = 0; i < n; ++i) {
      const std::uint32_t slot = first + static_cast<std::uint32_t>(i);
      bool found = false;
      for (const std::uint64_t* e = begin[i]; e != end[i]; ++e) {
        const auto s = static_cast<std::uint32_t>(*e);
        EXPECT_EQ(index.arc(s).from, from[i]);
        EXPECT_EQ(index.arc(s).to, to[i]);
        found = found || s == slot;
      }
      ASSERT_TRUE(found) << "arc in slot " << slot << " not in its row";
      EXPECT_EQ(end[i] - begin[i], (arcs_of_pair[{from[i], to[i]}]));
    }
  }
  // Every target, present or not, from every 7th keypoint: most look-ups
  // of the selection are of pairs without an arc.
  const std::uint32_t keypoints = index.keypoint_count();
  for (std::uint32_t from = 0; from < keypoints; from += 7) {
    for (std::uint32_t first = 0; first < keypoints; first += kBatch) {
      const int n = static_cast<int>(std::min<std::uint32_t>(kBatch, keypoints - first));
      std::uint32_t froms[kBatch], tos[kBatch];
      for (int i = 0; i < n; ++i) {
        froms[i] = from;
        tos[i] = first + static_cast<std::uint32_t>(i);
      }
      const std::uint64_t* begin[kBatch];
      const std::uint64_t* end[kBatch];
      adjacency.find(froms, tos, n, begin, end);
      for (int i = 0; i < n; ++i) {
        const auto pair = arcs_of_pair.find({from, tos[i]});
        ASSERT_EQ(end[i] - begin[i], pair == arcs_of_pair.end() ? 0 : pair->second)
            << from << " -> " << tos[i];
      }
    }
  }
  // The rows hold the cases the blocks make special: a row whose length is
  // a multiple of the block, and a pair whose arcs span two blocks.
  bool whole_blocks = false, spanning = false;
  std::uint32_t row = 0, position = 0;
  for (const auto& [pair, count] : arcs_of_pair) {
    if (pair.first != row) {
      whole_blocks = whole_blocks || (position > 0 && position % ArcAdjacency::kBlock == 0);
      row = pair.first;
      position = 0;
    }
    const auto last = position + static_cast<std::uint32_t>(count) - 1;
    spanning = spanning || position / ArcAdjacency::kBlock != last / ArcAdjacency::kBlock;
    position = last + 1;
  }
  EXPECT_TRUE(whole_blocks);
  EXPECT_TRUE(spanning);
}

// The same for 4-circuits, whose middle lists are cut against both
// neighbours' kept arcs.
TEST(Selection, FourCircuitsEqualBruteForceJoinOnRealImages) {
  const Case& c = the_case(Structure::kCircuit4);
  // Fewer than with triangles: all four arcs must be similar.
  ASSERT_GE(c.expected.size(), 10u);
  double kept = 1.0;
  expect_brute_force_set(c, Limits{}, &kept);
  EXPECT_LT(kept, 0.20);  // measured 12.5 % (2.4 % with the single model image)
}

// Arc keygraphs: every model arc similar to the scene arc, no join.
TEST(Selection, ArcsEqualBruteForceOnRealImages) {
  const Case& c = the_case(Structure::kArc);
  ASSERT_GT(c.expected.size(), 1000u);
  Limits limits;
  limits.max_correspondences = 1 << 20;  // one per similar model arc
  expect_brute_force_set(c, limits);
}

// When the frame's pool of model arcs fills up, later look-ups are cut
// short: the selection is then a subset of the full one, still correct,
// and says so.
TEST(Selection, TruncatedArcPoolSelectsASubset) {
  const Case& c = the_case();
  // The frame holds the box: many correspondences (none: the case failed to build).
  ASSERT_GT(c.expected.size(), 50u);
  DetectStats full_stats;
  Limits full_limits;
  const std::set<Match> full = select_all(c, full_limits, full_stats);
  ASSERT_EQ(full, c.expected);
  for (int pool : {20000, 3000, 500}) {
    Limits limits;
    limits.max_arc_pool = pool;
    DetectStats stats;
    const std::set<Match> part = select_all(c, limits, stats);
    EXPECT_TRUE(stats.truncated_arc_matches) << "pool " << pool;
    EXPECT_LT(part.size(), full.size()) << "pool " << pool;
    EXPECT_TRUE(std::includes(full.begin(), full.end(), part.begin(), part.end()))
        << "pool " << pool << ": a correspondence the full selection does not make";
  }
}

}  // namespace
}  // namespace kg

namespace kg {
namespace {

// The search budget grows with the square root of the index's models
// beyond the reference (format 6.3), capped, and stays as recorded when
// either parameter turns the growth off.
TEST(ArcSearchBudget, GrowsWithTheSquareRootOfTheModelsBeyondTheReference) {
  DescriptorParams p;
  ASSERT_EQ(p.max_search_leaves, 8);
  ASSERT_EQ(p.search_reference_models, 10);
  p.max_search_leaves = 20;  // the figures of format 6.3's default
  EXPECT_EQ(ArcSearch::leaves_for(p, 1), 20);
  EXPECT_EQ(ArcSearch::leaves_for(p, 10), 20);
  EXPECT_EQ(ArcSearch::leaves_for(p, 40), 40);  // 4x the models: 2x the leaves
  EXPECT_EQ(ArcSearch::leaves_for(p, 50), 45);
  EXPECT_EQ(ArcSearch::leaves_for(p, 89), 60);   // 2.98x: just below the cap
  EXPECT_EQ(ArcSearch::leaves_for(p, 202), 60);  // capped at 3x
  EXPECT_EQ(ArcSearch::leaves_for(p, 1'000'000), 60);
  p.max_search_leaves = 2'000'000'000;  // no overflow at the cap
  EXPECT_EQ(ArcSearch::leaves_for(p, 1'000'000), std::numeric_limits<int>::max());
  p.max_search_leaves = 20;
  p.search_reference_models = 0;  // files before 6.3: a fixed budget
  EXPECT_EQ(ArcSearch::leaves_for(p, 1'000'000), 20);
  p.search_reference_models = 10;
  p.max_search_leaves = 0;  // exact search stays exact
  EXPECT_EQ(ArcSearch::leaves_for(p, 1'000'000'000), 0);
}

}  // namespace
}  // namespace kg
