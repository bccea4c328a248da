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
//     // optional: local optimisation (below)
//     bool fit_within(const Model& from, double factor, Model& out);
//   };
//
// Local optimisation (LO-RANSAC, Chum et al. 2003), as PoseLib's loop:
// when a hypothesis beats the best so far it is refitted, the refit scored
// and kept when it is better still, up to kRefineRounds times while it
// gains. An estimator with `fit_within` (a least-squares fit to the data
// within `factor` times its inlier threshold of `from`) gets LO-RANSAC's
// iterated least squares (Lebeda, Matas and Chum, BMVC 2012): fits with a
// threshold shrinking from kLocalWidest times the inlier threshold to 1x,
// each scored, beside the plain refit on the inliers; the best of them is
// the refit. A hypothesis from samples in one part of the data fits that
// part; the wider threshold reaches the rest (a sign under perspective),
// which a refit on the hypothesis's own inliers reaches slowly or never.
// The adaptive iteration count then follows the refit's inlier ratio, so good models stop the loop
// sooner; stats.refinements counts the refits that improved the best.
//
// Progressive sampling (PROSAC, Chum & Matas 2005): when the estimator's
// samples are ordered best first (RansacOptions::progressive), hypotheses
// are drawn from a prefix of the pool that grows on PROSAC's schedule, so
// that likely-inlier samples are tried first and the adaptive count is
// reached sooner; once the prefix is the whole pool, draws are uniform. An
// enumerated small pool is then walked in colexicographic order (every
// combination of the best m samples before any with sample m + 1) and stops
// by the same adaptive rule instead of trying every combination.
//
// The adaptive iteration count uses the fraction of *samples* that are
// inliers (score.sample_inliers / sample_count): for keygraphs, a keygraph
// correspondence is an inlier when all keypoint correspondences it implies
// are. Hypotheses are compared by score.point_inliers, then by lower
// score.cost.
#pragma once

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>

#include "core/support/rng.h"

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
  // Samples are ordered best first: draw and enumerate progressively
  // (PROSAC, above). The whole pool's stopping rule is kept;
  // prefix_min_sample_inliers adds PROSAC's rule on prefixes.
  bool progressive = false;
  // PROSAC's maximality on prefixes: with an estimator that reports its
  // inlier samples (`bool sample_inlier(int) const`, after score()), stop
  // once some prefix U_m holding at least this many inlier samples of the
  // best model has had enough draws for its own inlier fraction; 0: only
  // the whole pool's rule. The floor stands in for PROSAC's non-randomness
  // test: any hypothesis makes its own h samples inliers.
  int prefix_min_sample_inliers = 0;
  // PROSAC's T_N: the number of draws over which the prefix would grow to
  // the whole pool if sampled as often as uniform draws sample it (the
  // paper's 200 000).
  int progressive_horizon = 200000;
  // Stop after this many draws while the best model so far (if any) has
  // fewer than least_point_inliers or least_sample_inliers: a pool in which
  // that many draws found nothing useful holds no instance the rest of the
  // budget would find (0: never; docs/RESULTS.md, "RANSAC on barren pools").
  int barren_draws = 0;
  int least_point_inliers = 0;
  int least_sample_inliers = 0;
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

// Advances `s` (h increasing indices) to the next combination in
// colexicographic order: all combinations of {0..m-1} come before any that
// holds m. Unbounded: the caller stops after C(n, h) combinations.
inline void next_combination_colex(int* s, int h) {
  int i = 0;
  while (i + 1 < h && s[i] + 1 == s[i + 1]) ++i;
  ++s[i];
  for (int j = 0; j < i; ++j) s[j] = j;
}

// PROSAC's growth schedule (Chum & Matas 2005, section 2.2) for a pool of n
// samples ordered best first, hypotheses of h samples: draw t (1-based)
// samples from the prefix U_m, m the largest size whose start T'_m <= t,
// always with the prefix's newest sample m - 1 and h - 1 others from U_{m-1};
// T'_h = 1, T'_{m+1} = T'_m + min(ceil(T_{m+1} - T_m), C(m - 1, h - 1)) with
// T_m the expected count of draws from U_m among `horizon` uniform draws.
// The cap is the number of distinct samples U_m adds: a prefix is not drawn
// from more often than it has new combinations, so the prefix keeps
// growing when the horizon is far beyond the iteration cap instead of
// redrawing the same hypotheses (PROSAC's paper assumes T_N draws are run).
// Once the prefix is the whole pool, uniform.
class ProgressiveSampler {
 public:
  ProgressiveSampler(int n, int h, int horizon) : n_(n), h_(h), size_(h) {
    assert(h > 0 && h <= n);
    double t = horizon;
    for (int i = 0; i < h; ++i) t *= static_cast<double>(h - i) / (n - i);
    t_size_ = t;
    next_start_ = start_after(1);
  }
  int prefix() const { return size_; }
  // The draws that lie wholly inside the current prefix U_m (m < n) over
  // the whole schedule: those before it grows past m, T'_{m+1} - 1.
  long long draws_inside_prefix() const { return next_start_ - 1; }
  // Grows the prefix by one sample, as draws do when they reach T'_{m+1}.
  void grow() {
    const long long start = next_start_;
    t_size_ = t_size_ * (size_ + 1) / (size_ + 1 - h_);
    ++size_;
    next_start_ = size_ < n_ ? start_after(start) : start;
  }
  void draw(Rng& rng, int t, int* out) {
    while (size_ < n_ && next_start_ <= t) grow();
    if (size_ >= n_) {
      draw_distinct(rng, n_, h_, out);
      return;
    }
    out[0] = size_ - 1;
    if (h_ > 1) draw_distinct(rng, size_ - 1, h_ - 1, out + 1);
  }

 private:
  // T'_{size+1} from T'_size = `start`.
  long long start_after(long long start) const {
    const double t_next = t_size_ * (size_ + 1) / (size_ + 1 - h_);
    const auto expected = static_cast<long long>(std::ceil(t_next - t_size_));
    // Distinct draws while the prefix is U_size: its newest sample and h - 1
    // of the size - 1 before it.
    const long long distinct = combinations_up_to(size_ - 1, h_ - 1, expected);
    return start + std::max(1LL, std::min(expected, distinct));
  }
  int n_, h_, size_;
  double t_size_;         // T_size
  long long next_start_;  // T'_{size+1}
};

// An estimator may draw its own samples (e.g. neighbourhood-guided) by
// providing `void draw(Rng&, int* sample)`; otherwise samples are uniform.
template <class E, class = void>
struct has_custom_draw : std::false_type {};
template <class E>
struct has_custom_draw<
    E, std::void_t<decltype(std::declval<E&>().draw(std::declval<Rng&>(), std::declval<int*>()))>>
    : std::true_type {};

// An estimator may fit a model to the data near another one:
// `bool fit_within(const Model& from, double factor, Model& out)`.
template <class E, class = void>
struct has_fit_within : std::false_type {};
template <class E>
struct has_fit_within<E, std::void_t<decltype(std::declval<E&>().fit_within(
                             std::declval<const typename E::Model&>(), std::declval<double>(),
                             std::declval<typename E::Model&>()))>> : std::true_type {};

// An estimator may say which samples the last scored model explains:
// `bool sample_inlier(int) const` (for the prefix stopping rule).
template <class E, class = void>
struct has_sample_inlier : std::false_type {};
template <class E>
struct has_sample_inlier<
    E, std::void_t<decltype(std::declval<const E&>().sample_inlier(std::declval<int>()))>>
    : std::true_type {};

// An estimator may score a hypothesis against the best so far:
// `RansacScore score_if_better(const Model&, const RansacScore& best)`, the
// score (and flags) of score() when better_score() says it beats best, any
// score that does not otherwise (it may stop early: most hypotheses lose).
template <class E, class = void>
struct has_score_if_better : std::false_type {};
template <class E>
struct has_score_if_better<
    E, std::void_t<decltype(std::declval<E&>().score_if_better(
           std::declval<const typename E::Model&>(), std::declval<const RansacScore&>()))>>
    : std::true_type {};

inline constexpr int kRefineRounds = 4;
// LO-RANSAC's iterated least squares: kLocalSteps fits, the first with
// kLocalWidest times the inlier threshold (the paper's values).
inline constexpr double kLocalWidest = 3.0;
inline constexpr int kLocalSteps = 4;

inline bool better_score(const RansacScore& a, const RansacScore& b) {
  return a.point_inliers > b.point_inliers ||
         (a.point_inliers == b.point_inliers && a.cost < b.cost);
}

// The fewest draws after which some prefix U_m (m < n) of the ordered pool
// with at least prefix_min_sample_inliers inlier samples of the last scored
// model has been sampled enough for its own inlier fraction (confidence
// P), counting only the draws that lie inside U_m; the cap when none has.
template <class Estimator>
int prefix_required(const Estimator& estimator, const RansacOptions& options, int n, int h,
                    bool enumerate) {
  int best = options.max_iterations;
  int inliers = 0;
  // The schedule's prefix walked along with m (draws inside U_m).
  ProgressiveSampler schedule(n, h, std::max(1, options.progressive_horizon));
  long long combinations = 1;  // C(m, h), enumeration
  for (int m = 1; m < n; ++m) {
    inliers += estimator.sample_inlier(m - 1) ? 1 : 0;
    if (m < h) continue;
    if (m > h) {
      if (enumerate) combinations = combinations * m / (m - h);  // small: C(n, h) <= the cap
      schedule.grow();
    }
    if (inliers < options.prefix_min_sample_inliers) continue;
    const int required = required_iterations(static_cast<double>(inliers) / m, h,
                                             options.confidence, options.max_iterations);
    const long long inside = enumerate ? combinations : schedule.draws_inside_prefix();
    if (required <= inside) best = std::min(best, required);
  }
  return best;
}

// One local optimisation of `model` (scored `s`; the estimator's flags are
// its): the best of the plain refit (factor 1) and each step of the
// iterated least squares. True, with `model`, `s` and the flags those of
// the refit, when it is better; otherwise all are left as they were.
template <class Estimator>
bool local_optimisation(Estimator& estimator, typename Estimator::Model& model, RansacScore& s) {
  typename Estimator::Model best = model, fit = model;
  RansacScore best_score = s;
  bool improved = false;
  bool flags_of_best = true;  // the estimator's flags are best's
  const auto consider = [&]() {
    const RansacScore r = estimator.score(fit);
    flags_of_best = better_score(r, best_score);
    if (flags_of_best) {
      best = fit;
      best_score = r;
      improved = true;
    }
  };
  if (estimator.fit_within(model, 1.0, fit)) consider();
  typename Estimator::Model current = model;
  for (int step = 0; step < kLocalSteps; ++step) {
    const double factor = kLocalWidest - (kLocalWidest - 1.0) * step / (kLocalSteps - 1);
    if (!estimator.fit_within(current, factor, fit)) break;
    consider();
    current = fit;
  }
  // The flags of the model returned (the last one scored may be another).
  if (!flags_of_best) estimator.score(best);
  if (!improved) return false;
  model = best;
  s = best_score;
  return true;
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
  // Progressive enumeration stops by the adaptive rule; plain enumeration
  // tries every combination.
  const bool enumerate_all = enumerate && !options.progressive;
  if (enumerate) {
    stats.required_iterations = static_cast<int>(all);
    for (int i = 0; i < h; ++i) next_sample[i] = i;
  }
  ProgressiveSampler progressive(n, h, std::max(1, options.progressive_horizon));
  bool more = true;
  while (more && stats.iterations < options.max_iterations &&
         (enumerate_all || stats.iterations < options.min_iterations ||
          stats.iterations < stats.required_iterations)) {
    if (options.barren_draws > 0 && stats.iterations >= options.barren_draws &&
        !(have_best && stats.best.point_inliers >= options.least_point_inliers &&
          stats.best.sample_inliers >= options.least_sample_inliers))
      break;
    ++stats.iterations;
    if (enumerate) {
      std::copy(next_sample, next_sample + h, sample);
      if (options.progressive) {
        next_combination_colex(next_sample, h);
        more = stats.iterations < all;
      } else {
        more = next_combination(next_sample, h, n);
      }
    } else if constexpr (has_custom_draw<Estimator>::value) {
      estimator.draw(rng, sample);
    } else if (options.progressive) {
      progressive.draw(rng, stats.iterations, sample);
    } else {
      draw_distinct(rng, n, h, sample);
    }
    if (!estimator.hypothesis(sample, model)) continue;
    ++stats.valid_hypotheses;
    RansacScore s;
    if constexpr (has_score_if_better<Estimator>::value) {
      s = have_best ? estimator.score_if_better(model, stats.best) : estimator.score(model);
    } else {
      s = estimator.score(model);
    }
    if (have_best && !better_score(s, stats.best)) continue;
    if constexpr (has_fit_within<Estimator>::value) {
      for (int round = 0; round < kRefineRounds; ++round) {
        if (!local_optimisation(estimator, model, s)) break;
        ++stats.refinements;
      }
    }
    have_best = true;
    stats.best = s;
    best_model = model;
    if (!enumerate_all) {
      int required = required_iterations(static_cast<double>(s.sample_inliers) / n, h,
                                         options.confidence, options.max_iterations);
      // The prefix rule counts the progressive schedule's draws: not with an
      // estimator that draws its own samples.
      if constexpr (has_sample_inlier<Estimator>::value && !has_custom_draw<Estimator>::value) {
        if (options.progressive && options.prefix_min_sample_inliers > 0)
          required = std::min(required, prefix_required(estimator, options, n, h, enumerate));
      }
      stats.required_iterations =
          enumerate ? static_cast<int>(std::min<long long>(all, required)) : required;
    }
  }
  return stats;
}

}  // namespace kg
