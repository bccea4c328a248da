#include "core/pose/pose.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/index/index_format.h"
#include "core/keygraphs/keygraph.h"
#include "core/pose/confidence.h"
#include "core/pose/homography.h"
#include "core/pose/keygraph_estimator.h"
#include "core/pose/ransac.h"

namespace kg {

namespace {

// Poses whose keypoint support (verification z) is below this share of the
// lowest z a detection needs are not aligned with the model's appearance:
// on the tuning sets no pose below a z of 6 was accepted, and without the
// alignment z does not change (docs/RESULTS.md, "Frame cost cut").
constexpr double kAlignZShare = 0.5;

// A cluster only the small rule could accept is refined and verified when
// its RANSAC pose's longest side is within this factor of
// ransac.small_max_size (the refinement moves a pose's corners by pixels).
constexpr float kSmallPoseMargin = 1.5f;

// Whether an instance with these corners repeats one of `model_id` already
// in `out`. A second RANSAC attempt on the left-over correspondences of one
// instance finds the same sign again, slightly shifted.
bool repeats_instance(const DetectionList& out, int model_id, const Point2f* corners) {
  for (const Detection& d : out) {
    if (d.model_id == model_id && outlines_overlap(d.corners, corners)) return true;
  }
  return false;
}

// Whether an instance of `model_id` in `out` and this outline hold each
// other's centres: a cluster on an instance already found, which
// repeats_instance() then rejects whatever its alignment does.
bool holds_an_instance(const DetectionList& out, int model_id, const Point2f* corners) {
  for (const Detection& d : out) {
    if (d.model_id == model_id && outlines_hold_each_other(d.corners, corners)) return true;
  }
  return false;
}

// The longest side of an outline, in frame pixels.
float longest_side(const Point2f* corners) {
  float longest = 0.f;
  for (int c = 0; c < 4; ++c) {
    const Point2f a = corners[c], b = corners[(c + 1) % 4];
    longest = std::max(longest, std::hypot(a.x - b.x, a.y - b.y));
  }
  return longest;
}

}  // namespace

PoseEstimator::PoseEstimator(std::pmr::memory_resource* memory)
    : pairs_(memory),
      pair_model_(memory),
      pair_scene_(memory),
      match_pairs_(memory),
      pair_inlier_(memory),
      pair_dead_(memory),
      match_active_(memory),
      pair_votes_(memory),
      match_quality_(memory),
      active_(memory),
      match_affine_(memory),
      inlier_model_(memory),
      inlier_scene_(memory),
      guided_model_(memory),
      guided_scene_(memory),
      aligner_(memory) {}

void PoseEstimator::reserve(int max_matches, int k, std::uint32_t max_model_keypoints,
                            int max_appearance_pixels) {
  const auto n = static_cast<std::size_t>(std::max(0, max_matches));
  const std::size_t pairs = n * static_cast<std::size_t>(k);
  pairs_.reserve(pairs);
  pair_model_.reserve(pairs);
  pair_scene_.reserve(pairs);
  match_pairs_.reserve(pairs);
  pair_inlier_.reserve(pairs);
  pair_dead_.reserve(pairs);
  match_active_.reserve(n);
  pair_votes_.reserve(pairs);
  match_quality_.reserve(n);
  active_.reserve(n);
  match_affine_.reserve(n);
  inlier_model_.reserve(pairs);
  inlier_scene_.reserve(pairs);
  guided_model_.reserve(max_model_keypoints);
  guided_scene_.reserve(max_model_keypoints);
  aligner_.reserve(max_appearance_pixels);
}

PoseEstimator::Support PoseEstimator::guided_pairs(const ModelIndex& index, const RansacParams& rp,
                                                   const ModelInfo& info,
                                                   const FrameKeypoints& frame,
                                                   const Homography& h) {
  const Point2f* model_points = index.keypoints() + info.keypoint_begin;
  guided_model_.clear();
  guided_scene_.clear();
  int inside = 0;
  for_each_shown_keypoint(index, rp, info, frame, h, {0.f, 0.f},
                          [&](std::uint32_t i, Point2f p, float radius) {
                            ++inside;
                            const int j = frame.grid->nearest(p, radius);
                            if (j < 0) return;
                            guided_model_.push_back(model_points[i]);
                            guided_scene_.push_back({frame.keypoints[j].x, frame.keypoints[j].y});
                          });
  Support support;
  support.inside = inside;
  support.fraction = inside > 0 ? static_cast<double>(guided_model_.size()) / inside : 0.0;
  return support;
}

PoseEstimator::Support PoseEstimator::guided_refine(const ModelIndex& index, const Params& params,
                                                    const ModelInfo& info,
                                                    const FrameKeypoints& frame, Homography& h) {
  const RansacParams& rp = params.ransac;
  Support support;
  for (int round = 0; round < 2; ++round) {
    support = guided_pairs(index, rp, info, frame, h);
    if (guided_model_.size() < 8) break;
    Homography candidate = h;
    refine_homography(guided_model_.data(), guided_scene_.data(),
                      static_cast<int>(guided_model_.size()), candidate);
    if (!is_plausible_pose(candidate, info.width, info.height, rp,
                           smallest_area_scale(params, info.width, info.height)))
      break;
    h = candidate;
  }
  return support;
}

int PoseEstimator::estimate(const ModelIndex& index, const Params& params, int model_id,
                            const KeygraphMatch* matches, int n, const Point2f* scene_points,
                            const FrameKeypoints& frame, Rng& rng, int max_out, DetectionList& out,
                            bool& truncated) {
  const RansacParams& rp = params.ransac;
  const int k = vertex_count(params.graph.structure);
  const int h = sample_size(params.graph.structure);
  if (n < h) return 0;
  const ModelInfo info = index.model(model_id);
  const Point2f* model_points = index.keypoints();

  // Distinct keypoint correspondences (model id << 32 | scene index).
  pairs_.clear();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < k; ++j) {
      pairs_.push_back((static_cast<std::uint64_t>(matches[i].model_vertices[j]) << 32) |
                       static_cast<std::uint32_t>(matches[i].scene_vertices[j]));
    }
  }
  std::sort(pairs_.begin(), pairs_.end());
  pairs_.erase(std::unique(pairs_.begin(), pairs_.end()), pairs_.end());
  const std::size_t pair_count = pairs_.size();
  pair_model_.resize(pair_count);
  pair_scene_.resize(pair_count);
  pair_inlier_.assign(pair_count, 0);
  pair_dead_.assign(pair_count, 0);
  for (std::size_t i = 0; i < pair_count; ++i) {
    pair_model_[i] = model_points[pairs_[i] >> 32];
    pair_scene_[i] = scene_points[pairs_[i] & 0xFFFFFFFFu];
  }
  match_pairs_.resize(static_cast<std::size_t>(n) * k);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < k; ++j) {
      const std::uint64_t key = (static_cast<std::uint64_t>(matches[i].model_vertices[j]) << 32) |
                                static_cast<std::uint32_t>(matches[i].scene_vertices[j]);
      match_pairs_[static_cast<std::size_t>(i) * k + j] = static_cast<std::uint32_t>(
          std::lower_bound(pairs_.begin(), pairs_.end(), key) - pairs_.begin());
    }
  }
  match_active_.assign(static_cast<std::size_t>(n), 1);
  // Two-match hypotheses are pre-tested with each match's local affine map
  // through its first three points (core/pose/local_affine.h).
  match_affine_.clear();
  if (h == 2 && k >= 3) {
    for (int i = 0; i < n; ++i) {
      Point2f m[3], sc[3];
      for (int j = 0; j < 3; ++j) {
        const std::uint32_t p = match_pairs_[static_cast<std::size_t>(i) * k + j];
        m[j] = pair_model_[p];
        sc[j] = pair_scene_[p];
      }
      match_affine_.push_back(local_affine(m, sc));
    }
  }
  // ransac.progressive_sampling (format 6.4; 0, as in older files: uniform draws).
  const bool progressive = rp.progressive_sampling != 0;
  if (progressive) {
    // Each match's quality for progressive sampling: how often its keypoint
    // correspondences occur in other matches (once per shared pair). Correct circuits of one object
    // overlap (neighbouring triangles share edges in the model and the frame
    // alike); wrong ones rarely agree on a model keypoint for a frame one.
    pair_votes_.assign(pair_count, 0);
    for (std::uint32_t p : match_pairs_) ++pair_votes_[p];
    match_quality_.resize(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      int votes = 0;
      for (int j = 0; j < k; ++j)
        votes += pair_votes_[match_pairs_[static_cast<std::size_t>(i) * k + j]];
      match_quality_[static_cast<std::size_t>(i)] = votes - k;
    }
  }

  KeygraphEstimator estimator{*this,
                              k,
                              h,
                              info.width,
                              info.height,
                              rp,
                              smallest_area_scale(params, info.width, info.height),
                              rp.inlier_threshold * rp.inlier_threshold};
  RansacOptions options;
  options.confidence = rp.confidence;
  options.max_iterations = rp.max_iterations;
  options.enumerate_small_pools = true;
  // Correspondences ordered by shared pairs (above), PROSAC's schedule;
  // a prefix holding 16 inlier correspondences of the best pose may end the
  // search early (a floor of 4 or 8 stopped on wrong clusters of the sign
  // benchmark's small signs; docs/RESULTS.md, "Progressive sampling").
  options.progressive = progressive;
  options.prefix_min_sample_inliers = progressive ? 16 : 0;
  // The model's appearance, when the index and the frame allow aligning it;
  // poses it confirms may have less keypoint support.
  const ModelAppearance stored = index.appearance(model_id);
  const bool can_align = !stored.empty() && !frame.image.empty();
  // Small instances' poses (ransac.small_*) need their appearance too.
  const bool small_rule = can_align && rp.small_max_size > 0.f && rp.small_min_inliers > 0;
  const int large_least = can_align && rp.confirmed_min_inliers > 0
                              ? std::min(rp.min_inliers, rp.confirmed_min_inliers)
                              : rp.min_inliers;
  const int least_inliers = small_rule ? std::min(large_least, rp.small_min_inliers) : large_least;
  // Once the best cluster left is too weak for a large instance, only the
  // small rule may accept (without it the search ended there).
  bool small_only = false;
  // Clusters below this verification z are not aligned (below): a share
  // of the lowest z a detection can have; none when the verification is off.
  const double lowest_z =
      can_align && rp.confirmed_min_inliers > 0
          ? std::min(rp.min_verification_z, static_cast<double>(rp.confirmed_min_verification_z))
          : rp.min_verification_z;
  const double align_min_z =
      lowest_z > 0.0 ? kAlignZShare * lowest_z : -std::numeric_limits<double>::infinity();
  // The lowest appearance an acceptance rule takes: an alignment abandoned
  // below it (DetectOptions::align_coarse_min_ncc) rejects its cluster.
  double lowest_appearance = rp.min_appearance;
  if (can_align && rp.confirmed_min_inliers > 0)
    lowest_appearance =
        std::min(lowest_appearance, static_cast<double>(rp.confirmed_min_appearance));
  if (small_rule)
    lowest_appearance = std::min(lowest_appearance, static_cast<double>(rp.small_min_appearance));
  // An abandoned alignment reports the pose's own correlation, counted as
  // at least 0 (below): with no rule above 0 nothing is abandoned.
  const double abandon_below =
      lowest_appearance > 0.0 ? std::min(align_coarse_min_ncc_, lowest_appearance) : -2.0;
  const double refuse_below =
      lowest_appearance > 0.0 ? std::min(align_min_ncc_, lowest_appearance) : -2.0;
  // An attempt whose draws found nothing that could make an instance
  // stops early (DetectOptions::ransac_barren_draws): the cap's draws go
  // mostly to models absent from the frame.
  options.barren_draws = barren_draws_;
  options.least_point_inliers = least_inliers;
  options.least_sample_inliers = rp.min_inlier_keygraphs;
  int iterations = 0;
  // Each attempt finds one instance or rules out one false cluster.
  for (int attempt = 0; attempt < rp.max_instances; ++attempt) {
    active_.clear();
    for (int i = 0; i < n; ++i) {
      if (match_active_[i]) active_.push_back(i);
    }
    if (static_cast<int>(active_.size()) < std::max(h, rp.min_inlier_keygraphs)) break;
    if (progressive) {
      // Best first (ties in selection order) for RansacOptions::progressive.
      std::sort(active_.begin(), active_.end(), [this](int a, int b) {
        const int qa = match_quality_[static_cast<std::size_t>(a)];
        const int qb = match_quality_[static_cast<std::size_t>(b)];
        return qa != qb ? qa > qb : a < b;
      });
    }
    Homography best{};
    const RansacStats stats = ransac(estimator, options, rng, best);
    iterations += stats.iterations;
    // The best cluster left cannot make an instance: neither can weaker ones.
    if (stats.best.point_inliers < least_inliers ||
        stats.best.sample_inliers < rp.min_inlier_keygraphs)
      break;
    small_only = small_only || stats.best.point_inliers < large_least;
    if (small_only) {
      // Only the small rule could accept it: a pose far larger than a small
      // instance is passed over before its refinement and verification,
      // which cost more than its RANSAC on a frame of many weak clusters.
      Point2f found[4];
      for (int c = 0; c < 4; ++c) found[c] = kg::apply(best, info.outline[c]);
      if (!(longest_side(found) <= kSmallPoseMargin * rp.small_max_size)) {
        estimator.score(best);  // its inlier flags
        explain_cluster(k);
        continue;
      }
    }

    // Refine on the inliers, re-selecting them with the refined pose.
    Homography refined = best;
    double rms = 0.0;
    RansacScore final_score = estimator.score(refined);
    for (int round = 0; round < 2; ++round) {
      inlier_model_.clear();
      inlier_scene_.clear();
      for (std::size_t i = 0; i < pair_count; ++i) {
        if (!pair_inlier_[i]) continue;
        inlier_model_.push_back(pair_model_[i]);
        inlier_scene_.push_back(pair_scene_[i]);
      }
      if (inlier_model_.size() < 4) break;
      Homography candidate = refined;
      rms = refine_homography(inlier_model_.data(), inlier_scene_.data(),
                              static_cast<int>(inlier_model_.size()), candidate);
      const RansacScore s = estimator.score(candidate);
      if (s.point_inliers < final_score.point_inliers) {
        estimator.score(refined);  // restore the inlier flags of the kept pose
        break;
      }
      refined = candidate;
      final_score = s;
    }

    // A cluster on an instance of this model already found (the outlines
    // hold each other's centres) repeats it: rejected either way
    // (repeats_instance, below), so it is neither refined further nor
    // aligned (align_coarse_min_ncc -1: judged in full, as before).
    const bool skip_repeats = align_coarse_min_ncc_ > -1.0;
    if (skip_repeats && !out.empty()) {
      Point2f at[4];
      for (int c = 0; c < 4; ++c) at[c] = kg::apply(refined, info.outline[c]);
      if (holds_an_instance(out, model_id, at)) {
        explain_cluster(k);  // the inliers of `refined`
        continue;
      }
    }

    // Guided refinement over all model keypoints, then the support that
    // the descriptors gave is recounted under the final pose.
    Support support = guided_refine(index, params, info, frame, refined);
    // Photometric refinement: the model's appearance aligned onto the frame
    // takes the corners from keypoint accuracy to sub-pixel, and its
    // correlation checks the identity (core/pose/appearance_align.h).
    double appearance = -1.0;  // -1: not measured
    double chance = chance_fraction(index, rp, info, frame, refined);
    // Binomial z-score of the re-found model keypoints against chance.
    double z = support_z(support.fraction, chance, support.inside);
    // A cluster whose keypoint support is far below what even a confirmed
    // detection needs is not aligned: it is rejected either way (z decides
    // without an appearance), and an alignment costs more than the rest of
    // the model's pose estimation (docs/RESULTS.md, "Frame cost cut").
    // A cluster only the small rule could accept is aligned only when its
    // pose is small: an alignment is most of a model's pose cost.
    Point2f corners[4];
    for (int c = 0; c < 4; ++c) corners[c] = kg::apply(refined, info.outline[c]);
    const bool worth_aligning = !small_only || longest_side(corners) <= rp.small_max_size;
    // The same for a pose that the guided refinement brought onto one.
    const bool repeat = skip_repeats && holds_an_instance(out, model_id, corners);
    if (can_align && z >= align_min_z && worth_aligning && !repeat) {
      Homography aligned = refined;
      const AppearanceFit fit =
          aligner_.align({stored.pixels, stored.width, stored.height, stored.scale, stored.scale},
                         frame.image, aligned, abandon_below, refuse_below);
      ++align_counts_.aligned;
      align_counts_.abandoned += fit.abandoned ? 1 : 0;
      if (fit.measured) {
        // The correlation of the pose kept; a negative one counts as none.
        const bool keep = fit.aligned && is_plausible_pose(aligned, info.width, info.height, rp,
                                                           estimator.min_area);
        appearance = std::max(0.0, keep ? fit.ncc : fit.ncc_before);
        if (keep) {
          refined = aligned;
          support = guided_pairs(index, rp, info, frame, refined);
          chance = chance_fraction(index, rp, info, frame, refined);
          z = support_z(support.fraction, chance, support.inside);
        }
      }
    }
    final_score = estimator.score(refined);

    const int distinct = distinct_inlier_points();
    for (int c = 0; c < 4; ++c) corners[c] = kg::apply(refined, info.outline[c]);
    // Enough keypoint support, and an appearance that does not contradict
    // it; or less support that the appearance confirms.
    const bool measured = appearance >= 0.0;
    const bool supported = distinct >= rp.min_inliers && z >= rp.min_verification_z &&
                           (!measured || appearance >= rp.min_appearance);
    const bool confirmed =
        measured && rp.confirmed_min_inliers > 0 && distinct >= rp.confirmed_min_inliers &&
        z >= rp.confirmed_min_verification_z && appearance >= rp.confirmed_min_appearance;
    // A small instance with fewer inliers still: its keypoints confirm it
    // as a large one's do (z), its appearance confirms it independently.
    const bool small = small_rule && measured && distinct >= rp.small_min_inliers &&
                       z >= rp.min_verification_z && appearance >= rp.small_min_appearance &&
                       longest_side(corners) <= rp.small_max_size;
    const bool accepted =
        (small || (!small_only && (supported || confirmed))) &&
        final_score.sample_inliers >= rp.min_inlier_keygraphs &&
        is_plausible_pose(refined, info.width, info.height, rp, estimator.min_area) &&
        !repeats_instance(out, model_id, corners);
    if (accepted && static_cast<int>(out.size()) >= max_out) {
      truncated = true;
      break;
    }
    if (accepted) {
      Detection d;
      d.model_id = model_id;
      d.model_name = info.name;
      d.homography = refined;
      for (int c = 0; c < 4; ++c) d.corners[c] = corners[c];
      d.inliers = distinct;
      d.inlier_keygraphs = final_score.sample_inliers;
      d.score = support.fraction;
      d.chance = chance;
      d.rms_error = rms;
      d.verification_z = z;
      d.appearance = appearance;
      d.confidence = detection_confidence(d);
      d.ransac_iterations = stats.iterations;
      out.push_back(d);
    }
    // Accepted or not, this cluster of correspondences is explained (by an
    // instance or as a false cluster); the next attempt looks elsewhere.
    explain_cluster(k);
  }
  return iterations;
}

int PoseEstimator::distinct_inlier_points() {
  // Distinct scene keypoints among the inliers (a scene point explained
  // twice counts once).
  inlier_scene_.clear();
  for (std::size_t i = 0; i < pair_inlier_.size(); ++i) {
    if (pair_inlier_[i]) inlier_scene_.push_back(pair_scene_[i]);
  }
  std::sort(inlier_scene_.begin(), inlier_scene_.end(),
            [](Point2f a, Point2f b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  int distinct = 0;
  for (std::size_t i = 0; i < inlier_scene_.size(); ++i) {
    if (i == 0 || inlier_scene_[i].x != inlier_scene_[i - 1].x ||
        inlier_scene_[i].y != inlier_scene_[i - 1].y)
      ++distinct;
  }
  return distinct;
}

void PoseEstimator::explain_cluster(int k) {
  // Remove every correspondence that touches the cluster's inliers.
  for (int i : active_) {
    const std::uint32_t* ids = &match_pairs_[static_cast<std::size_t>(i) * k];
    for (int j = 0; j < k; ++j) {
      if (pair_inlier_[ids[j]]) {
        match_active_[i] = 0;
        break;
      }
    }
  }
  // Its keypoint correspondences no longer count for later instances.
  for (std::size_t i = 0; i < pair_inlier_.size(); ++i) {
    if (pair_inlier_[i]) pair_dead_[i] = 1;
    pair_inlier_[i] = 0;
  }
}

}  // namespace kg
