// The RANSAC estimator of the pose (paper section 7): its samples are
// keygraph correspondences, its hypotheses homographies through their
// keypoint correspondences, its score the distinct keypoint correspondences
// they all imply (core/pose/ransac.h runs the loop). Internal to
// pose.cpp, over the PoseEstimator's buffers.
#pragma once

#include <cmath>
#include <cstdint>

#include "core/keygraphs/keygraph.h"
#include "core/pose/homography.h"
#include "core/pose/pose.h"
#include "core/pose/ransac.h"
#include "keygraph/params.h"

namespace kg {

// Tolerance of the pre-test below: localisation noise plus a fraction of
// the distance over which a local affine map is extrapolated (perspective
// bends it), both in scene pixels.
inline constexpr float kPretestPixels = 3.f;
inline constexpr float kPretestFraction = 0.25f;

// Whether the affine map through the three correspondences (m0, s0)
// predicts the scene points s1 of the model points m1 (n of them) within
// the pre-test tolerance. Degenerate triangles fail.
inline bool affine_predicts(const Point2f* m0, const Point2f* s0, const Point2f* m1,
                            const Point2f* s1, int n) {
  const float m00 = m0[1].x - m0[0].x, m01 = m0[2].x - m0[0].x, m10 = m0[1].y - m0[0].y,
              m11 = m0[2].y - m0[0].y;
  const float det = m00 * m11 - m01 * m10;
  if (!(std::fabs(det) > 1e-3f)) return false;
  const float inv = 1.f / det;
  const float s00 = s0[1].x - s0[0].x, s01 = s0[2].x - s0[0].x, s10 = s0[1].y - s0[0].y,
              s11 = s0[2].y - s0[0].y;
  // A = S M^-1 maps model offsets from m0[0] to scene offsets from s0[0].
  const float a = (s00 * m11 - s01 * m10) * inv, b = (-s00 * m01 + s01 * m00) * inv;
  const float c = (s10 * m11 - s11 * m10) * inv, d = (-s10 * m01 + s11 * m00) * inv;
  const float cx = (s0[0].x + s0[1].x + s0[2].x) / 3.f, cy = (s0[0].y + s0[1].y + s0[2].y) / 3.f;
  for (int i = 0; i < n; ++i) {
    const float dx = m1[i].x - m0[0].x, dy = m1[i].y - m0[0].y;
    const float px = s0[0].x + a * dx + b * dy, py = s0[0].y + c * dx + d * dy;
    const float ex = px - s1[i].x, ey = py - s1[i].y;
    const float fx = s1[i].x - cx, fy = s1[i].y - cy;
    const float tol = kPretestPixels + kPretestFraction * std::sqrt(fx * fx + fy * fy);
    if (ex * ex + ey * ey > tol * tol) return false;
  }
  return true;
}

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
      Point2f m[2][kMaxVertices], sc[2][kMaxVertices];
      for (int i = 0; i < 2; ++i) {
        const std::uint32_t* pairs =
            &s.match_pairs_[static_cast<std::size_t>(s.active_[sample[i]]) * k];
        for (int j = 0; j < k; ++j) {
          m[i][j] = s.pair_model_[pairs[j]];
          sc[i][j] = s.pair_scene_[pairs[j]];
        }
      }
      if (!affine_predicts(m[0], sc[0], m[1], sc[1], k) ||
          !affine_predicts(m[1], sc[1], m[0], sc[0], k))
        return false;
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
    const std::size_t pairs = s.pairs_.size();
    for (std::size_t i = 0; i < pairs; ++i) {
      const Point2f p = kg::apply(hom, s.pair_model_[i]);
      const double dx = p.x - s.pair_scene_[i].x, dy = p.y - s.pair_scene_[i].y;
      const double e2 = dx * dx + dy * dy;
      const bool in = e2 < threshold2 && !s.pair_dead_[i];
      s.pair_inlier_[i] = in ? 1 : 0;
      r.point_inliers += in ? 1 : 0;
      r.cost += in ? e2 : threshold2;
    }
    for (int m : s.active_) {
      const std::uint32_t* ids = &s.match_pairs_[static_cast<std::size_t>(m) * k];
      bool all = true;
      for (int j = 0; j < k && all; ++j) all = s.pair_inlier_[ids[j]] != 0;
      r.sample_inliers += all ? 1 : 0;
    }
    return r;
  }
};

// The RANSAC loop's local optimisation needs fit_within (ransac.h); without
// it the loop would silently skip it.
static_assert(has_fit_within<KeygraphEstimator>::value);

}  // namespace kg
