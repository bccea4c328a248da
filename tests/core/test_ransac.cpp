// The generic RANSAC loop: a homography from point correspondences with
// 80 % outliers, the adaptive iteration count, the cap and reproducibility.
#include "core/pose/ransac.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <utility>
#include <vector>

#include "core/pose/homography.h"
#include "core/support/rng.h"

namespace kg {
namespace {

constexpr float kModelW = 640.f;
constexpr float kModelH = 480.f;
const Homography kTruth = {0.7629, -0.2992,  225.67,    0.3344, 1.0144,
                           -77.0,  3.466e-4, -1.436e-5, 1.0};

double gaussian(Rng& rng) {
  const double u1 = 1.0 - rng.uniform01();
  const double u2 = rng.uniform01();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

double reprojection(const Homography& h, Point2f m, Point2f s) {
  const Point2f p = kg::apply(h, m);
  return std::hypot(p.x - s.x, p.y - s.y);
}

// Each sample is one point correspondence; four give a homography.
struct PointEstimator {
  using Model = Homography;
  const std::vector<Point2f>* model = nullptr;
  const std::vector<Point2f>* scene = nullptr;
  double threshold = 3.0;
  int hypotheses = 0;

  int sample_count() const { return static_cast<int>(model->size()); }
  int sample_size() const { return 4; }
  bool hypothesis(const int* samples, Model& out) {
    ++hypotheses;
    Point2f m[4];
    Point2f s[4];
    for (int i = 0; i < 4; ++i) {
      m[i] = (*model)[samples[i]];
      s[i] = (*scene)[samples[i]];
    }
    return fit_homography(m, s, 4, out);
  }
  RansacScore score(const Model& h) const {
    RansacScore r;
    for (std::size_t i = 0; i < model->size(); ++i) score_point(h, i, r);
    r.sample_inliers = r.point_inliers;
    return r;
  }
  // Adds point i to r; whether it is an inlier.
  bool score_point(const Model& h, std::size_t i, RansacScore& r) const {
    const double e = reprojection(h, (*model)[i], (*scene)[i]);
    if (e < threshold) {
      ++r.point_inliers;
      r.cost += e * e;
      return true;
    }
    r.cost += threshold * threshold;
    return false;
  }
};

struct Correspondences {
  std::vector<Point2f> model;
  std::vector<Point2f> scene;
  int inliers = 0;
};

// `inliers` true correspondences with Gaussian noise, then `outliers`
// random pairs, shuffled so that inliers are not a prefix.
Correspondences make_correspondences(int inliers, int outliers, double sigma, std::uint64_t seed) {
  Rng rng(seed);
  Correspondences c;
  c.inliers = inliers;
  for (int i = 0; i < inliers + outliers; ++i) {
    const Point2f m{static_cast<float>(rng.uniform01() * kModelW),
                    static_cast<float>(rng.uniform01() * kModelH)};
    Point2f s;
    if (i < inliers) {
      const Point2f t = kg::apply(kTruth, m);
      s = {static_cast<float>(t.x + sigma * gaussian(rng)),
           static_cast<float>(t.y + sigma * gaussian(rng))};
    } else {
      s = {static_cast<float>(rng.uniform01() * 900.0),
           static_cast<float>(rng.uniform01() * 700.0)};
    }
    c.model.push_back(m);
    c.scene.push_back(s);
  }
  for (int i = static_cast<int>(c.model.size()) - 1; i > 0; --i) {
    const int j = static_cast<int>(rng.uniform(static_cast<std::uint32_t>(i + 1)));
    std::swap(c.model[i], c.model[j]);
    std::swap(c.scene[i], c.scene[j]);
  }
  return c;
}

TEST(Ransac, RecoversHomographyWithEightyPercentOutliers) {
  const Correspondences c = make_correspondences(60, 240, 0.5, 21);
  PointEstimator est;
  est.model = &c.model;
  est.scene = &c.scene;
  RansacOptions options;
  options.max_iterations = 20000;
  Rng rng(99);
  Homography best{};
  const RansacStats stats = ransac(est, options, rng, best);
  ASSERT_GT(stats.valid_hypotheses, 0);
  // Nearly all 60 true correspondences, and few of the outliers by chance.
  EXPECT_GE(stats.best.point_inliers, 55);
  EXPECT_LE(stats.best.point_inliers, 70);
  EXPECT_EQ(stats.iterations, est.hypotheses);
  EXPECT_EQ(stats.required_iterations,
            required_iterations(static_cast<double>(stats.best.sample_inliers) / 300, 4,
                                options.confidence, options.max_iterations));
  EXPECT_LE(stats.iterations, stats.required_iterations);

  // Refit and refine on the inliers of the best hypothesis.
  std::vector<Point2f> in_model;
  std::vector<Point2f> in_scene;
  for (std::size_t i = 0; i < c.model.size(); ++i) {
    if (reprojection(best, c.model[i], c.scene[i]) < est.threshold) {
      in_model.push_back(c.model[i]);
      in_scene.push_back(c.scene[i]);
    }
  }
  const int n = static_cast<int>(in_model.size());
  Homography h{};
  ASSERT_TRUE(fit_homography(in_model.data(), in_scene.data(), n, h));
  const double rms = refine_homography(in_model.data(), in_scene.data(), n, h);
  EXPECT_LT(rms, 1.0);
  EXPECT_TRUE(is_plausible_pose(h, kModelW, kModelH, RansacParams{}));
  const Point2f corners[4] = {{0.f, 0.f}, {kModelW, 0.f}, {kModelW, kModelH}, {0.f, kModelH}};
  for (const Point2f& q : corners) {
    const Point2f got = kg::apply(h, q);
    const Point2f want = kg::apply(kTruth, q);
    EXPECT_LT(std::hypot(got.x - want.x, got.y - want.y), 2.0) << "corner " << q.x << "," << q.y;
  }
}

TEST(Ransac, SameSeedGivesSameResult) {
  const Correspondences c = make_correspondences(60, 240, 0.5, 22);
  RansacOptions options;
  options.max_iterations = 20000;
  Homography first{};
  Homography second{};
  PointEstimator a;
  a.model = &c.model;
  a.scene = &c.scene;
  PointEstimator b = a;
  Rng r1(5);
  Rng r2(5);
  const RansacStats s1 = ransac(a, options, r1, first);
  const RansacStats s2 = ransac(b, options, r2, second);
  EXPECT_EQ(s1.iterations, s2.iterations);
  EXPECT_EQ(s1.valid_hypotheses, s2.valid_hypotheses);
  EXPECT_EQ(s1.best.point_inliers, s2.best.point_inliers);
  EXPECT_EQ(s1.best.cost, s2.best.cost);
  EXPECT_EQ(first, second);
  // The random state advanced identically too.
  EXPECT_EQ(r1.next(), r2.next());
}

// PointEstimator that scores against the best so far (ransac.h's
// score_if_better): it stops once too many points are outliers.
struct BoundedPointEstimator : PointEstimator {
  int stopped = 0;  // scorings that stopped early
  RansacScore score_if_better(const Model& h, const RansacScore& best) {
    RansacScore r;
    const int most_outliers = static_cast<int>(model->size()) - best.point_inliers;
    int outliers = 0;
    for (std::size_t i = 0; i < model->size(); ++i) {
      if (!score_point(h, i, r) && ++outliers > most_outliers) {
        ++stopped;
        return r;
      }
    }
    r.sample_inliers = r.point_inliers;
    return r;
  }
};
static_assert(has_score_if_better<BoundedPointEstimator>::value);
static_assert(!has_score_if_better<PointEstimator>::value);

TEST(Ransac, ScoringAgainstTheBestGivesTheSameResult) {
  const Correspondences c = make_correspondences(60, 240, 0.5, 23);
  RansacOptions options;
  options.max_iterations = 3000;
  PointEstimator plain;
  plain.model = &c.model;
  plain.scene = &c.scene;
  BoundedPointEstimator bounded;
  bounded.model = &c.model;
  bounded.scene = &c.scene;
  Rng r1(7);
  Rng r2(7);
  Homography first{};
  Homography second{};
  const RansacStats s1 = ransac(plain, options, r1, first);
  const RansacStats s2 = ransac(bounded, options, r2, second);
  EXPECT_GT(bounded.stopped, s2.valid_hypotheses / 2);  // most hypotheses lose early
  EXPECT_EQ(s1.iterations, s2.iterations);
  EXPECT_EQ(s1.valid_hypotheses, s2.valid_hypotheses);
  EXPECT_EQ(s1.required_iterations, s2.required_iterations);
  EXPECT_EQ(s1.best.point_inliers, s2.best.point_inliers);
  EXPECT_EQ(s1.best.sample_inliers, s2.best.sample_inliers);
  EXPECT_EQ(s1.best.cost, s2.best.cost);
  EXPECT_EQ(first, second);
  EXPECT_EQ(r1.next(), r2.next());
}

// Reports the same score for every hypothesis: `sample_inliers` of
// `samples` samples are inliers. Every `degenerate_every`-th hypothesis
// (when > 0) is degenerate. Records each drawn sample.
struct FixedFractionEstimator {
  using Model = int;
  int samples = 100;
  int size = 3;
  int sample_inliers = 40;
  int degenerate_every = 0;
  int calls = 0;
  std::vector<std::vector<int>> drawn;

  int sample_count() const { return samples; }
  int sample_size() const { return size; }
  bool hypothesis(const int* s, Model& out) {
    drawn.emplace_back(s, s + size);
    out = ++calls;
    return degenerate_every <= 0 || calls % degenerate_every != 0;
  }
  RansacScore score(const Model&) const {
    RansacScore r;
    r.point_inliers = sample_inliers;
    r.sample_inliers = sample_inliers;
    return r;
  }
};

TEST(Ransac, AdaptiveIterationCountMatchesFormula) {
  FixedFractionEstimator est;  // p = 0.4, h = 3
  RansacOptions options;
  options.max_iterations = 1000;
  Rng rng(1);
  int best = 0;
  const RansacStats stats = ransac(est, options, rng, best);
  // ceil(log(0.01) / log(1 - 0.4^3)) = ceil(69.6) = 70.
  const int expected = static_cast<int>(std::ceil(std::log(0.01) / std::log(1.0 - 0.064)));
  ASSERT_EQ(expected, 70);
  EXPECT_EQ(required_iterations(0.4, 3, 0.99, 1000), expected);
  EXPECT_EQ(stats.required_iterations, expected);
  EXPECT_EQ(stats.iterations, expected);
  EXPECT_EQ(stats.valid_hypotheses, expected);
  EXPECT_EQ(est.calls, expected);
  // Equal scores never replace the first best.
  EXPECT_EQ(best, 1);
  EXPECT_EQ(stats.best.sample_inliers, 40);
  // Every sample is `size` distinct indices in range.
  for (const auto& s : est.drawn) {
    ASSERT_EQ(s.size(), 3u);
    for (int i = 0; i < 3; ++i) {
      EXPECT_GE(s[i], 0);
      EXPECT_LT(s[i], 100);
      for (int j = 0; j < i; ++j) EXPECT_NE(s[i], s[j]);
    }
  }
}

TEST(Ransac, DegenerateHypothesesStillCountAsIterations) {
  FixedFractionEstimator est;
  est.sample_inliers = 80;  // p = 0.8: ceil(log(0.01) / log(1 - 0.512)) = 7
  est.degenerate_every = 2;
  RansacOptions options;
  Rng rng(2);
  int best = 0;
  const RansacStats stats = ransac(est, options, rng, best);
  EXPECT_EQ(required_iterations(0.8, 3, 0.99, options.max_iterations), 7);
  EXPECT_EQ(stats.iterations, 7);
  EXPECT_EQ(stats.valid_hypotheses, 4);  // calls 1, 3, 5, 7
}

TEST(Ransac, IterationCapAndMinimum) {
  FixedFractionEstimator est;
  est.sample_inliers = 1;  // p = 0.01: about 4.6 million iterations needed
  RansacOptions options;
  options.max_iterations = 500;
  Rng rng(3);
  int best = 0;
  RansacStats stats = ransac(est, options, rng, best);
  EXPECT_EQ(stats.required_iterations, 500);
  EXPECT_EQ(stats.iterations, 500);

  // min_iterations overrides an early adaptive stop, but not the cap.
  FixedFractionEstimator easy;
  easy.sample_inliers = 95;
  options.min_iterations = 50;
  stats = ransac(easy, options, rng, best);
  EXPECT_LT(stats.required_iterations, 50);
  EXPECT_EQ(stats.iterations, 50);
  options.max_iterations = 20;
  FixedFractionEstimator capped;
  capped.sample_inliers = 95;
  stats = ransac(capped, options, rng, best);
  EXPECT_EQ(stats.iterations, 20);

  // Too few samples for one minimal set: nothing is drawn.
  FixedFractionEstimator tiny;
  tiny.samples = 2;
  stats = ransac(tiny, options, rng, best);
  EXPECT_EQ(stats.iterations, 0);
  EXPECT_EQ(tiny.calls, 0);
}

TEST(Ransac, SmallPoolsAreEnumeratedOnce) {
  FixedFractionEstimator est;
  est.samples = 10;
  est.size = 2;
  est.sample_inliers = 1;  // would run to the cap if drawn at random
  RansacOptions options;
  options.max_iterations = 1000;
  options.enumerate_small_pools = true;
  Rng rng(4);
  const std::uint64_t untouched = Rng(4).next();
  int best = 0;
  const RansacStats stats = ransac(est, options, rng, best);
  EXPECT_EQ(stats.iterations, 45);  // C(10, 2)
  EXPECT_EQ(stats.required_iterations, 45);
  ASSERT_EQ(est.drawn.size(), 45u);
  std::set<std::pair<int, int>> seen;
  for (const auto& s : est.drawn) {
    ASSERT_EQ(s.size(), 2u);
    EXPECT_LT(s[0], s[1]);
    EXPECT_LT(s[1], 10);
    seen.insert({s[0], s[1]});
  }
  EXPECT_EQ(seen.size(), 45u);       // every pair, each once
  EXPECT_EQ(rng.next(), untouched);  // no random draws

  // Larger than the cap: random draws as usual.
  FixedFractionEstimator large;
  large.samples = 100;
  large.size = 2;
  large.sample_inliers = 1;
  options.max_iterations = 100;  // C(100, 2) = 4950
  const RansacStats capped = ransac(large, options, rng, best);
  EXPECT_EQ(capped.iterations, 100);
  EXPECT_EQ(combinations_up_to(100, 2, 100), 101);
  EXPECT_EQ(combinations_up_to(100, 2, 10000), 4950);
  EXPECT_EQ(combinations_up_to(7, 3, 1000), 35);
}

TEST(Ransac, ProgressiveSamplerFollowsThePrefixSchedule) {
  constexpr int kN = 200;
  constexpr int kH = 2;
  ProgressiveSampler sampler(kN, kH, 2000);
  Rng rng(5);
  int sample[kH];
  int last_prefix = 0;
  int reached_all_at = 0;
  for (int t = 1; t <= 4000; ++t) {
    sampler.draw(rng, t, sample);
    const int prefix = sampler.prefix();
    ASSERT_GE(prefix, last_prefix) << "the prefix never shrinks";
    last_prefix = prefix;
    if (t == 1) {
      // The first hypothesis is the two best samples.
      EXPECT_EQ(std::min(sample[0], sample[1]), 0);
      EXPECT_EQ(std::max(sample[0], sample[1]), 1);
    }
    EXPECT_NE(sample[0], sample[1]);
    for (int v : sample) {
      EXPECT_GE(v, 0);
      EXPECT_LT(v, prefix);
    }
    if (prefix < kN) {
      EXPECT_EQ(sample[0], prefix - 1) << "a new prefix's draws hold its newest sample";
    } else if (reached_all_at == 0) {
      reached_all_at = t;
    }
  }
  // T_m = T_N m(m-1) / (N(N-1)) draws from U_m: the whole pool at about the
  // horizon T_N, not before half of it (the ceilings round up).
  EXPECT_GT(reached_all_at, 1000);
  EXPECT_LE(reached_all_at, 2000 + kN);
  // Then uniform: the last samples are drawn from the whole pool.
  int high = 0;
  for (int t = 4001; t <= 4200; ++t) {
    sampler.draw(rng, t, sample);
    high += sample[0] >= kN / 2 ? 1 : 0;
  }
  EXPECT_GT(high, 60);
}

// A horizon far beyond the draws run: each prefix is drawn from at most as
// often as it has new combinations (its newest sample with one of the
// others), so the prefix still reaches the whole pool, by C(n, 2) draws.
TEST(Ransac, ProgressiveSamplerNeverOutdrawsAPrefix) {
  constexpr int kN = 60;
  ProgressiveSampler sampler(kN, 2, 200000);
  Rng rng(8);
  int sample[2];
  std::vector<int> draws_at(kN + 1, 0);
  int reached_all_at = 0;
  for (int t = 1; t <= 2000 && reached_all_at == 0; ++t) {
    sampler.draw(rng, t, sample);
    if (sampler.prefix() == kN) {
      reached_all_at = t;
    } else {
      ++draws_at[static_cast<std::size_t>(sampler.prefix())];
    }
  }
  for (int m = 2; m < kN; ++m) EXPECT_LE(draws_at[static_cast<std::size_t>(m)], m - 1) << m;
  EXPECT_GT(reached_all_at, 0);
  EXPECT_LE(reached_all_at, kN * (kN - 1) / 2 + 1);
}

TEST(Ransac, ProgressiveEnumerationIsColexicographic) {
  FixedFractionEstimator est;
  est.samples = 8;
  est.size = 3;
  est.sample_inliers = 1;  // never stops early
  RansacOptions options;
  options.max_iterations = 1000;
  options.enumerate_small_pools = true;
  options.progressive = true;
  Rng rng(6);
  int best = 0;
  const RansacStats stats = ransac(est, options, rng, best);
  EXPECT_EQ(stats.iterations, 56);  // C(8, 3)
  ASSERT_EQ(est.drawn.size(), 56u);
  std::set<std::vector<int>> seen;
  int largest = 0;
  for (std::size_t i = 0; i < est.drawn.size(); ++i) {
    const std::vector<int>& s = est.drawn[i];
    EXPECT_LT(s[0], s[1]);
    EXPECT_LT(s[1], s[2]);
    EXPECT_LT(s[2], 8);
    // Every combination of the best m samples before any with sample m:
    // the first C(m, 3) hold only samples below m.
    EXPECT_GE(s[2], largest);
    largest = s[2];
    seen.insert(s);
  }
  EXPECT_EQ(seen.size(), 56u);
  EXPECT_EQ((std::vector<int>{0, 1, 2}), est.drawn[0]);
  EXPECT_EQ((std::vector<int>{0, 1, 3}), est.drawn[1]);

  // A good pool stops by the adaptive rule instead of trying them all.
  FixedFractionEstimator good;
  good.samples = 8;
  good.size = 3;
  good.sample_inliers = 7;  // ceil(log(0.01) / log(1 - (7/8)^3)) = 5
  const RansacStats early = ransac(good, options, rng, best);
  EXPECT_EQ(required_iterations(7.0 / 8.0, 3, 0.99, 1000), 5);
  EXPECT_EQ(early.required_iterations, 5);
  EXPECT_EQ(early.iterations, 5);
}

// Samples ordered by a noisy quality (inliers score higher on average, as
// keygraph correspondences that share keypoint pairs with others do):
// within a budget far below what uniform draws need at 10 % inliers,
// progressive draws find the homography on every seed.
TEST(Ransac, ProgressiveDrawsFindPosesUniformDrawsMiss) {
  int progressive_found = 0, uniform_found = 0;
  constexpr int kSeeds = 10;
  for (int seed = 0; seed < kSeeds; ++seed) {
    const Correspondences raw = make_correspondences(30, 270, 0.5, 100 + seed);
    // Quality: an inlier's is higher on average, with overlap.
    Rng noise(200 + seed);
    std::vector<std::pair<double, int>> order;
    for (int i = 0; i < 300; ++i) {
      const Point2f t = kg::apply(kTruth, raw.model[static_cast<std::size_t>(i)]);
      const bool inlier = std::hypot(t.x - raw.scene[static_cast<std::size_t>(i)].x,
                                     t.y - raw.scene[static_cast<std::size_t>(i)].y) < 3.0;
      order.push_back({(inlier ? 1.0 : 0.0) + 0.6 * gaussian(noise), i});
    }
    std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a > b; });
    Correspondences c;
    for (const auto& [quality, i] : order) {
      c.model.push_back(raw.model[static_cast<std::size_t>(i)]);
      c.scene.push_back(raw.scene[static_cast<std::size_t>(i)]);
    }
    for (const bool progressive : {true, false}) {
      PointEstimator est;
      est.model = &c.model;
      est.scene = &c.scene;
      RansacOptions options;
      options.max_iterations = 300;  // uniform draws need about 46 000 at 10 %
      options.progressive = progressive;
      Rng rng(300 + seed);
      Homography best{};
      const RansacStats stats = ransac(est, options, rng, best);
      // At least half the 30 true correspondences (a minimal sample of
      // noisy points, no local optimisation here, keeps 18 to 30 of them).
      const bool found = stats.best.point_inliers >= 15;
      (progressive ? progressive_found : uniform_found) += found ? 1 : 0;
    }
  }
  EXPECT_EQ(progressive_found, kSeeds);
  EXPECT_LE(uniform_found, 2);
}

// PointEstimator that also says which samples its last scored model
// explains (for the prefix stopping rule).
struct FlaggingPointEstimator : PointEstimator {
  std::vector<char> inlier;
  RansacScore score(const Model& h) {
    inlier.assign(model->size(), 0);
    for (std::size_t i = 0; i < model->size(); ++i)
      inlier[i] = reprojection(h, (*model)[i], (*scene)[i]) < threshold ? 1 : 0;
    return PointEstimator::score(h);
  }
  bool sample_inlier(int i) const { return inlier[static_cast<std::size_t>(i)] != 0; }
};

// The best 30 of 200 samples are all inliers (40 in all): the whole
// pool's fraction (0.2) asks for about 2 900 draws, the prefix's for a few,
// and the rule counts only draws inside that prefix.
TEST(Ransac, PrefixRuleStopsOnceAnInlierPrefixIsSampledEnough) {
  const Correspondences raw = make_correspondences(40, 160, 0.3, 31);
  Correspondences c;
  std::vector<int> rest;
  for (int i = 0; i < 200; ++i) {
    const auto u = static_cast<std::size_t>(i);
    const Point2f t = kg::apply(kTruth, raw.model[u]);
    const bool inlier = std::hypot(t.x - raw.scene[u].x, t.y - raw.scene[u].y) < 3.0;
    if (inlier && c.model.size() < 30) {
      c.model.push_back(raw.model[u]);
      c.scene.push_back(raw.scene[u]);
    } else {
      rest.push_back(i);
    }
  }
  ASSERT_EQ(c.model.size(), 30u);
  for (int i : rest) {
    c.model.push_back(raw.model[static_cast<std::size_t>(i)]);
    c.scene.push_back(raw.scene[static_cast<std::size_t>(i)]);
  }
  RansacOptions options;
  options.max_iterations = 5000;
  options.progressive = true;
  const auto run = [&](int prefix_floor) {
    FlaggingPointEstimator est;
    est.model = &c.model;
    est.scene = &c.scene;
    options.prefix_min_sample_inliers = prefix_floor;
    Rng rng(7);
    Homography best{};
    return ransac(est, options, rng, best);
  };
  const RansacStats whole = run(0);
  const RansacStats prefix = run(8);
  EXPECT_GE(whole.best.point_inliers, 38);
  EXPECT_GE(prefix.best.point_inliers, 38);
  EXPECT_EQ(whole.required_iterations,
            required_iterations(static_cast<double>(whole.best.sample_inliers) / 200, 4,
                                options.confidence, options.max_iterations));
  EXPECT_GT(whole.iterations, 2000);
  EXPECT_LT(prefix.iterations, 100);
  EXPECT_LE(prefix.required_iterations, prefix.iterations);  // stopped by the rule, not the cap
}

// With fit_within: LO-RANSAC's iterated least squares (ransac.h). Records
// the last model scored (the flags an estimator keeps are that model's).
struct LocalPointEstimator : PointEstimator {
  int fits = 0;
  Homography last_scored{};
  RansacScore score(const Homography& h) {
    last_scored = h;
    return PointEstimator::score(h);
  }
  bool fit_within(const Homography& from, double factor, Homography& out) {
    ++fits;
    std::vector<Point2f> m, s;
    for (std::size_t i = 0; i < model->size(); ++i) {
      if (!(reprojection(from, (*model)[i], (*scene)[i]) < threshold * factor)) continue;
      m.push_back((*model)[i]);
      s.push_back((*scene)[i]);
    }
    return m.size() >= 8 && fit_homography(m.data(), s.data(), static_cast<int>(m.size()), out);
  }
};

// A perspective view whose keypoints lie in one corner (40) and in the far
// half (260), nothing between (a sign's symbol and its text), plus 100
// outliers; the corner's own fit.
struct TwoRegions {
  std::vector<Point2f> model, scene;
  Homography corner_fit{};
};

TwoRegions two_regions() {
  constexpr float kCorner = 0.15f;       // of the model's width and height
  constexpr std::size_t kInCorner = 40;  // keypoints in the corner
  Rng rng(21);
  TwoRegions t;
  std::vector<Point2f> corner_model, corner_scene;
  while (t.model.size() < 300) {
    const Point2f m{static_cast<float>(rng.uniform01() * kModelW),
                    static_cast<float>(rng.uniform01() * kModelH)};
    const bool corner = m.x < kCorner * kModelW && m.y < kCorner * kModelH;
    const bool far = m.x > 0.55f * kModelW;
    if (corner ? corner_model.size() >= kInCorner
               : !far || t.model.size() - corner_model.size() >= 300 - kInCorner)
      continue;
    const Point2f p = kg::apply(kTruth, m);
    const Point2f s{static_cast<float>(p.x + 0.7 * gaussian(rng)),
                    static_cast<float>(p.y + 0.7 * gaussian(rng))};
    t.model.push_back(m);
    t.scene.push_back(s);
    if (corner) {
      corner_model.push_back(m);
      corner_scene.push_back(s);
    }
  }
  for (int i = 0; i < 100; ++i) {  // outliers
    t.model.push_back({static_cast<float>(rng.uniform01() * kModelW),
                       static_cast<float>(rng.uniform01() * kModelH)});
    t.scene.push_back(
        {static_cast<float>(rng.uniform01() * 900.0), static_cast<float>(rng.uniform01() * 700.0)});
  }
  fit_homography(corner_model.data(), corner_scene.data(), static_cast<int>(corner_model.size()),
                 t.corner_fit);
  return t;
}

// The corner's fit explains the corner (40 of 300); refits on its own
// inliers, repeated while they gain (the refine of estimators without
// fit_within), stay there (40); one local optimisation (its threshold
// starts at 3x) reaches the far half too (300). The estimator's last scored model is the one
// returned.
TEST(Ransac, LocalOptimisationReachesTheWholeViewFromOneCorner) {
  const TwoRegions t = two_regions();
  LocalPointEstimator e;
  e.model = &t.model;
  e.scene = &t.scene;
  const RansacScore at_start = e.score(t.corner_fit);
  Homography plain = t.corner_fit;
  RansacScore after_plain = at_start;
  for (int round = 0; round < 20; ++round) {
    Homography fit{};
    if (!e.fit_within(plain, 1.0, fit)) break;
    const RansacScore r = e.score(fit);
    if (!better_score(r, after_plain)) break;
    plain = fit;
    after_plain = r;
  }
  Homography local = t.corner_fit;
  RansacScore after_local = at_start;
  ASSERT_TRUE(local_optimisation(e, local, after_local));
  EXPECT_EQ(e.last_scored, local);
  EXPECT_EQ(after_local.point_inliers, e.score(local).point_inliers);
  std::printf("inliers of 300: start %d, plain refits %d, local optimisation %d\n",
              at_start.point_inliers, after_plain.point_inliers, after_local.point_inliers);
  EXPECT_LE(after_plain.point_inliers, 60);
  EXPECT_GE(after_local.point_inliers, 297);
  EXPECT_LE(after_local.point_inliers, 300 + 3);  // hardly any outlier explained
  const Point2f corners[4] = {{0.f, 0.f}, {kModelW, 0.f}, {kModelW, kModelH}, {0.f, kModelH}};
  for (const Point2f& c : corners) {
    const Point2f truth = kg::apply(kTruth, c);
    const Point2f found = kg::apply(local, c);
    EXPECT_LT(std::hypot(found.x - truth.x, found.y - truth.y), 1.5);
  }
  // Not better than the score given: left as it was, its flags restored.
  Homography again = t.corner_fit;
  RansacScore unbeatable = at_start;
  unbeatable.point_inliers += 1000;
  EXPECT_FALSE(local_optimisation(e, again, unbeatable));
  EXPECT_EQ(again, t.corner_fit);
  EXPECT_EQ(unbeatable.point_inliers, at_start.point_inliers + 1000);
  EXPECT_EQ(e.last_scored, t.corner_fit);
}

// The loop runs the local optimisation of an estimator with fit_within on
// its new best hypotheses.
TEST(Ransac, LoopRunsTheLocalOptimisation) {
  const TwoRegions t = two_regions();
  LocalPointEstimator e;
  e.model = &t.model;
  e.scene = &t.scene;
  RansacOptions options;
  options.max_iterations = 2000;
  Rng rng(5);
  Homography best{};
  const RansacStats stats = ransac(e, options, rng, best);
  EXPECT_GT(e.fits, 0);
  EXPECT_GT(stats.refinements, 0);
  EXPECT_GE(stats.best.point_inliers, 297);
}

// RansacOptions::barren_draws: a pool of outliers alone stops after that
// many draws instead of at the cap; a pool holding an instance, whose draws
// soon find a hypothesis with the support asked for, runs as without it.
TEST(Ransac, BarrenPoolsStopEarly) {
  RansacOptions options;
  options.max_iterations = 3000;
  RansacOptions barren = options;
  barren.barren_draws = 200;
  barren.least_point_inliers = 12;
  barren.least_sample_inliers = 12;
  {
    const Correspondences c = make_correspondences(0, 300, 0.5, 5);
    PointEstimator est;
    est.model = &c.model;
    est.scene = &c.scene;
    Rng rng(3);
    Homography best{};
    const RansacStats full = ransac(est, options, rng, best);
    EXPECT_EQ(full.iterations, 3000);
    EXPECT_LT(full.best.point_inliers, 12);  // nothing an instance would need
    Rng rng2(3);
    est.hypotheses = 0;
    const RansacStats stopped = ransac(est, barren, rng2, best);
    EXPECT_EQ(stopped.iterations, 200);
    EXPECT_EQ(est.hypotheses, 200);
    EXPECT_LT(stopped.best.point_inliers, 12);
  }
  {
    const Correspondences c = make_correspondences(150, 150, 0.5, 6);
    PointEstimator est;
    est.model = &c.model;
    est.scene = &c.scene;
    Rng rng(4), rng2(4);
    Homography a{}, b{};
    const RansacStats full = ransac(est, options, rng, a);
    const RansacStats with = ransac(est, barren, rng2, b);
    EXPECT_GE(full.best.point_inliers, 140);
    EXPECT_EQ(with.iterations, full.iterations);
    EXPECT_EQ(with.best.point_inliers, full.best.point_inliers);
    EXPECT_EQ(with.best.cost, full.best.cost);
    EXPECT_EQ(a, b);
    EXPECT_EQ(rng.next(), rng2.next());
  }
}

TEST(Ransac, RequiredIterationsEdgeCases) {
  EXPECT_EQ(required_iterations(0.0, 4, 0.99, 2000), 2000);
  EXPECT_EQ(required_iterations(1.0, 4, 0.99, 2000), 1);
  EXPECT_EQ(required_iterations(1e-9, 4, 0.99, 2000), 2000);  // p^h underflows
  EXPECT_EQ(required_iterations(0.5, 4, 0.99, 2000), 72);     // ceil(71.3)
  EXPECT_EQ(required_iterations(0.5, 4, 0.99, 50), 50);
  // Never above the cap, even when every sample is an inlier.
  EXPECT_EQ(required_iterations(1.0, 4, 0.99, 0), 0);
}

}  // namespace
}  // namespace kg
