// One RANSAC loop for every estimator (PoseLib style). An estimator
// provides, for a pool of `sample_count()` samples (for keygraphs: keygraph
// correspondences), minimal hypotheses from `sample_size()` distinct samples,
// and a score:
//
//   struct Estimator {
//     using Model = ...;
//     int sample_count() const;
//     int sample_size() const;                       // h in log(1-P)/log(1-p^h)
//     bool hypothesis(const int* samples, Model& out);  // false: degenerate
//     RansacScore score(const Model& m);             // see below
//     bool refine(Model& m);  // optional: local optimisation (below)
//   };
//
// Local optimisation (LO-RANSAC, Chum et al. 2003), as PoseLib's loop:
// when a hypothesis beats the best so far, an estimator with `refine`
// re-fits it on the inliers that its score() just marked; the refit is
// scored and kept when it is better still, up to kRefineRounds times while
// it gains. The adaptive iteration count
// then follows the refit's inlier ratio, so good models stop the loop
// sooner; stats.refinements counts the refits that improved the best.
//
// The adaptive iteration count uses the fraction of *samples* that are
// inliers (score.sample_inliers / sample_count): for keygraphs, a keygraph
// correspondence is an inlier when all keypoint correspondences it implies
// are. Hypotheses are compared by score.point_inliers, then by lower
// score.cost.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>

#include "core/rng.h"

namespace kg {

struct RansacScore {
  int point_inliers = 0;   // e.g. distinct keypoint correspondences within threshold
  int sample_inliers = 0;  // samples (keygraph correspondences) entirely inlier
  double cost = 0.0;       // tie-breaker, lower is better (e.g. truncated error)
};

struct RansacOptions {
  double confidence = 0.99;
  int max_iterations = 2000;
  int min_iterations = 0;
  // When the pool has at most max_iterations minimal samples (C(n, h)),
  // try every one of them once, in order, instead of drawing at random:
  // fewer hypotheses than the cap would draw, and none missed.
  bool enumerate_small_pools = false;
};

struct RansacStats {
  int iterations = 0;           // hypotheses drawn
  int valid_hypotheses = 0;     // hypotheses that were not degenerate
  int required_iterations = 0;  // adaptive bound at the end
  int refinements = 0;          // local optimisations that improved the best
  RansacScore best;
};

// Iterations needed to draw one all-inlier sample of size h with
// probability `confidence` when a fraction `inlier_ratio` of samples are
// inliers: log(1 - P) / log(1 - p^h), clamped to [0, cap].
inline int required_iterations(double inlier_ratio, int h, double confidence, int cap) {
  if (cap <= 0) return 0;  // never above the cap, even for inlier_ratio 1
  if (inlier_ratio <= 0.0) return cap;
  if (inlier_ratio >= 1.0) return 1;
  const double good = std::pow(inlier_ratio, h);
  if (good <= std::numeric_limits<double>::min()) return cap;
  const double denom = std::log1p(-good);
  if (denom >= 0.0) return cap;
  const double n = std::ceil(std::log1p(-confidence) / denom);
  if (!(n < static_cast<double>(cap))) return cap;
  return n < 1.0 ? 1 : static_cast<int>(n);
}

// Draws `k` distinct integers from [0, n) into out (k <= n, small k).
inline void draw_distinct(Rng& rng, int n, int k, int* out) {
  for (int i = 0; i < k; ++i) {
    for (;;) {
      const int v = static_cast<int>(rng.uniform(static_cast<std::uint32_t>(n)));
      bool fresh = true;
      for (int j = 0; j < i; ++j) fresh = fresh && out[j] != v;
      if (fresh) {
        out[i] = v;
        break;
      }
    }
  }
}

// C(n, h), or `cap` + 1 when larger than `cap`.
inline long long combinations_up_to(int n, int h, long long cap) {
  long long c = 1;
  for (int i = 0; i < h; ++i) {
    c = c * (n - i) / (i + 1);  // exact: a product of i + 1 consecutive integers
    if (c > cap) return cap + 1;
  }
  return c;
}

// Advances `s` (h increasing indices below n) to the next combination in
// lexicographic order; false after the last.
inline bool next_combination(int* s, int h, int n) {
  int i = h - 1;
  while (i >= 0 && s[i] == n - h + i) --i;
  if (i < 0) return false;
  ++s[i];
  for (int j = i + 1; j < h; ++j) s[j] = s[j - 1] + 1;
  return true;
}

// An estimator may draw its own samples (e.g. neighbourhood-guided) by
// providing `void draw(Rng&, int* sample)`; otherwise samples are uniform.
template <class E, class = void>
struct has_custom_draw : std::false_type {};
template <class E>
struct has_custom_draw<
    E, std::void_t<decltype(std::declval<E&>().draw(std::declval<Rng&>(), std::declval<int*>()))>>
    : std::true_type {};

// An estimator may refine a hypothesis on its inliers: `bool refine(Model&)`.
template <class E, class = void>
struct has_refine : std::false_type {};
template <class E>
struct has_refine<
    E, std::void_t<decltype(std::declval<E&>().refine(std::declval<typename E::Model&>()))>>
    : std::true_type {};

inline constexpr int kRefineRounds = 4;

inline bool better_score(const RansacScore& a, const RansacScore& b) {
  return a.point_inliers > b.point_inliers ||
         (a.point_inliers == b.point_inliers && a.cost < b.cost);
}

template <class Estimator>
RansacStats ransac(Estimator& estimator, const RansacOptions& options, Rng& rng,
                   typename Estimator::Model& best_model) {
  RansacStats stats;
  const int n = estimator.sample_count();
  const int h = estimator.sample_size();
  stats.required_iterations = options.max_iterations;
  if (n < h || h <= 0 || h > 8) return stats;
  int sample[8];
  int next_sample[8];  // enumeration: the combination after `sample`
  typename Estimator::Model model;
  bool have_best = false;
  const long long all = combinations_up_to(n, h, options.max_iterations);
  const bool enumerate = options.enumerate_small_pools && all <= options.max_iterations;
  if (enumerate) {
    stats.required_iterations = static_cast<int>(all);
    for (int i = 0; i < h; ++i) next_sample[i] = i;
  }
  bool more = true;
  while (more && stats.iterations < options.max_iterations &&
         (enumerate || stats.iterations < options.min_iterations ||
          stats.iterations < stats.required_iterations)) {
    ++stats.iterations;
    if (enumerate) {
      std::copy(next_sample, next_sample + h, sample);
      more = next_combination(next_sample, h, n);
    } else if constexpr (has_custom_draw<Estimator>::value) {
      estimator.draw(rng, sample);
    } else {
      draw_distinct(rng, n, h, sample);
    }
    if (!estimator.hypothesis(sample, model)) continue;
    ++stats.valid_hypotheses;
    RansacScore s = estimator.score(model);
    if (have_best && !better_score(s, stats.best)) continue;
    if constexpr (has_refine<Estimator>::value) {
      // Refit on the inliers while that gains (a few rounds at most).
      for (int round = 0; round < kRefineRounds; ++round) {
        typename Estimator::Model refined = model;
        if (!estimator.refine(refined)) break;
        const RansacScore r = estimator.score(refined);
        if (!better_score(r, s)) {
          estimator.score(model);  // the flags of the kept model
          break;
        }
        s = r;
        model = refined;
        ++stats.refinements;
      }
    }
    have_best = true;
    stats.best = s;
    best_model = model;
    if (!enumerate)
      stats.required_iterations = required_iterations(static_cast<double>(s.sample_inliers) / n, h,
                                                      options.confidence, options.max_iterations);
  }
  return stats;
}

}  // namespace kg
