// The RANSAC estimator of the pose (paper section 7): its samples are
// keygraph correspondences, its hypotheses homographies through their
// keypoint correspondences, its score the distinct keypoint correspondences
// they all imply (core/pose/ransac.h runs the loop). Internal to
// pose.cpp, over the PoseEstimator's buffers.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/keygraphs/keygraph.h"
#include "core/pose/homography.h"
#include "core/pose/local_affine.h"
#include "core/pose/pose.h"
#include "core/pose/ransac.h"
#include "keygraph/params.h"

namespace kg {

// RANSAC estimator over the active keygraph correspondences.
struct KeygraphEstimator {
  using Model = Homography;
  PoseEstimator& s;
  int k;
  int h;
  float model_w, model_h;
  const RansacParams& params;
  double min_area;  // smallest_area_scale() of the model
  double threshold2;

  int sample_count() const { return static_cast<int>(s.active_.size()); }
  int sample_size() const { return h; }

  bool hypothesis(const int* sample, Homography& out) {
    // Two circuits: each one's local affine map must predict the other's
    // points before the homography is fitted and scored. Rejects most
    // unrelated pairs for a few multiplications.
    if (h == 2 && k >= 3) {
      const auto m0 = static_cast<std::size_t>(s.active_[sample[0]]);
      const auto m1 = static_cast<std::size_t>(s.active_[sample[1]]);
      const LocalAffine& p = s.match_affine_[m0];
      const LocalAffine& q = s.match_affine_[m1];
      if (!affine_predicts(p, q) || !affine_predicts(q, p)) return false;
      // A 4-vertex circuit's fourth points (the maps are the first three's).
      for (int j = 3; j < k; ++j) {
        const std::uint32_t a = s.match_pairs_[m0 * static_cast<std::size_t>(k) + j];
        const std::uint32_t b = s.match_pairs_[m1 * static_cast<std::size_t>(k) + j];
        if (!affine_predicts_point(p, s.pair_model_[b], s.pair_scene_[b]) ||
            !affine_predicts_point(q, s.pair_model_[a], s.pair_scene_[a]))
          return false;
      }
    }
    Point2f model[kMaxVertices * 4];
    Point2f scene[kMaxVertices * 4];
    std::uint32_t ids[kMaxVertices * 4];
    int n = 0;
    for (int i = 0; i < h; ++i) {
      const std::uint32_t* pairs =
          &s.match_pairs_[static_cast<std::size_t>(s.active_[sample[i]]) * k];
      for (int j = 0; j < k; ++j) {
        const std::uint32_t p = pairs[j];
        bool seen = false;
        for (int q = 0; q < n && !seen; ++q) seen = ids[q] == p;
        if (seen) continue;
        // One model keypoint may not go to two scene keypoints, nor two to one.
        const std::uint64_t key = s.pairs_[p];
        for (int q = 0; q < n; ++q) {
          const std::uint64_t other = s.pairs_[ids[q]];
          if ((other >> 32) == (key >> 32) || (other & 0xFFFFFFFFu) == (key & 0xFFFFFFFFu))
            return false;
        }
        ids[n] = p;
        model[n] = s.pair_model_[p];
        scene[n] = s.pair_scene_[p];
        ++n;
      }
    }
    if (n < 4) return false;
    if (!fit_homography_hypothesis(model, scene, n, out)) return false;
    return is_plausible_pose(out, model_w, model_h, params, min_area);
  }

  // Local optimisation (ransac.h): the least-squares homography through the
  // keypoint correspondences within `factor` times the inlier threshold of
  // `from` (those of instances already found excluded).
  bool fit_within(const Homography& from, double factor, Homography& out) {
    const double limit2 = threshold2 * factor * factor;
    s.inlier_model_.clear();
    s.inlier_scene_.clear();
    for (std::size_t i = 0; i < s.pairs_.size(); ++i) {
      if (s.pair_dead_[i]) continue;
      const Point2f p = kg::apply(from, s.pair_model_[i]);
      const double dx = p.x - s.pair_scene_[i].x, dy = p.y - s.pair_scene_[i].y;
      if (!(dx * dx + dy * dy < limit2)) continue;  // NaN too, as score() counts it
      s.inlier_model_.push_back(s.pair_model_[i]);
      s.inlier_scene_.push_back(s.pair_scene_[i]);
    }
    const int n = static_cast<int>(s.inlier_model_.size());
    return n >= 6 &&
           fit_homography_hypothesis(s.inlier_model_.data(), s.inlier_scene_.data(), n, out) &&
           is_plausible_pose(out, model_w, model_h, params, min_area);
  }

  // Whether the last scored model explains sample i (all its pairs inliers).
  bool sample_inlier(int i) const {
    const std::uint32_t* ids = &s.match_pairs_[static_cast<std::size_t>(s.active_[i]) * k];
    for (int j = 0; j < k; ++j)
      if (!s.pair_inlier_[ids[j]]) return false;
    return true;
  }

  RansacScore score(const Homography& hom) {
    RansacScore r;
    score_pairs(hom, s.pairs_.size(), r);
    count_sample_inliers(r);
    return r;
  }

  // The score when it beats `best` (ransac.h); otherwise some score that
  // does not, the flags then left undefined. Most hypotheses lose: their
  // scoring stops once too few pairs are left to reach best's inliers, and
  // the samples are counted only for a winner.
  RansacScore score_if_better(const Homography& hom, const RansacScore& best) {
    RansacScore r;
    // More outliers than this leave fewer inliers than best's.
    const std::size_t pairs = s.pairs_.size();
    const std::size_t most_outliers =
        pairs - std::min(pairs, static_cast<std::size_t>(std::max(0, best.point_inliers)));
    // Stopped early, r's inliers are already below best's.
    if (!score_pairs(hom, most_outliers, r) || !better_score(r, best)) return r;
    count_sample_inliers(r);
    return r;
  }

  // Scores the pairs into r (point_inliers, cost) and their flags; false,
  // r partial, once more than most_outliers pairs are outliers.
  bool score_pairs(const Homography& hom, std::size_t most_outliers, RansacScore& r) {
    const std::size_t pairs = s.pairs_.size();
    std::size_t outliers = 0;
    for (std::size_t i = 0; i < pairs; ++i) {
      const Point2f p = kg::apply(hom, s.pair_model_[i]);
      const double dx = p.x - s.pair_scene_[i].x, dy = p.y - s.pair_scene_[i].y;
      const double e2 = dx * dx + dy * dy;
      const bool in = e2 < threshold2 && !s.pair_dead_[i];
      s.pair_inlier_[i] = in ? 1 : 0;
      r.point_inliers += in ? 1 : 0;
      r.cost += in ? e2 : threshold2;
      outliers += in ? 0 : 1;
      if (outliers > most_outliers) return false;
    }
    return true;
  }

  void count_sample_inliers(RansacScore& r) const {
    for (int m : s.active_) {
      const std::uint32_t* ids = &s.match_pairs_[static_cast<std::size_t>(m) * k];
      bool all = true;
      for (int j = 0; j < k && all; ++j) all = s.pair_inlier_[ids[j]] != 0;
      r.sample_inliers += all ? 1 : 0;
    }
  }
};

// The RANSAC loop's local optimisation needs fit_within (ransac.h); without
// it the loop would silently skip it.
static_assert(has_fit_within<KeygraphEstimator>::value);
static_assert(has_score_if_better<KeygraphEstimator>::value);

}  // namespace kg
