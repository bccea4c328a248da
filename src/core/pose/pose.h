// Pose estimation (paper section 7): RANSAC whose samples are keygraph
// correspondences. A hypothesis is the homography through the keypoint
// correspondences of sample_size(structure) keygraph correspondences; it is
// scored over the set of distinct keypoint correspondences they all imply
// (paper eq. 2). The best is refined by Levenberg-Marquardt on its inliers
// and accepted only if it is a plausible pose with enough support. Found
// instances' correspondences are removed and the search repeats, so one
// model can be found several times in a frame.
#pragma once

#include <cstdint>
#include <vector>

#include "core/pose/appearance_align.h"
#include "core/pose/local_affine.h"
#include "core/pose/overlap.h"
#include "core/pose/point_grid.h"
#include "core/pose/verification.h"
#include "core/support/rng.h"
#include "core/support/workspace.h"
#include "keygraph/detector.h"
#include "keygraph/model_index.h"

namespace kg {

class PoseEstimator {
 public:
  explicit PoseEstimator(std::pmr::memory_resource* memory = std::pmr::get_default_resource());
  // Sizes the buffers for up to max_matches keygraph correspondences of k
  // vertices, models of up to max_model_keypoints keypoints and appearance
  // images of up to max_appearance_pixels: estimate() then allocates nothing.
  void reserve(int max_matches, int k, std::uint32_t max_model_keypoints,
               int max_appearance_pixels);

  // Workers (nullptr: none) for the appearance alignment's frame sampling
  // (AppearanceAligner::set_workers): the same instances with or without.
  void set_workers(WorkerPool* workers) { aligner_.set_workers(workers); }

  // RANSAC stops a model's attempt after this many draws while nothing it
  // drew could make an instance (DetectOptions::ransac_barren_draws; 0: never).
  void set_barren_draws(int draws) { barren_draws_ = draws; }

  // A cluster's appearance alignment does not start when its pose
  // correlates under `before`, and stops after its coarse level when
  // neither its pose nor the coarse fit correlates at `coarse` or more
  // (each capped at the lowest appearance an acceptance rule takes),
  // rejecting it (DetectOptions::align_min_ncc, align_coarse_min_ncc; -1:
  // never). With `coarse` above -1 a cluster on an instance already found
  // is not refined nor aligned either.
  void set_align_min_ncc(double before, double coarse) {
    align_min_ncc_ = before;
    align_coarse_min_ncc_ = coarse;
  }

  // Appearance alignments run and abandoned after their coarse level, counted
  // over every estimate() since the estimator was made.
  struct AlignCounts {
    int aligned = 0;
    int abandoned = 0;
  };
  AlignCounts align_counts() const { return align_counts_; }

  // Appends the instances of `model_id` found among matches[0..n) (all of
  // that model) to `out`, at most `max_out` in total in `out`. Returns the
  // RANSAC iterations run.
  // `params` are the index's with the detector's options applied.
  int estimate(const ModelIndex& index, const Params& params, int model_id,
               const KeygraphMatch* matches, int n, const Point2f* scene_points,
               const FrameKeypoints& frame, Rng& rng, int max_out, DetectionList& out,
               bool& truncated);

 private:
  friend struct KeygraphEstimator;
  struct Support {
    int inside = 0;         // model keypoints projecting inside the frame
    double fraction = 0.0;  // of those, the fraction that found a frame keypoint
  };
  // Pairs every model keypoint the pose's scale shows with the nearest
  // frame keypoint within the verification radius (guided_model_,
  // guided_scene_) and returns the support they give.
  Support guided_pairs(const ModelIndex& index, const RansacParams& rp, const ModelInfo& info,
                       const FrameKeypoints& frame, const Homography& h);
  // Refines h on guided pairs and measures the support of the final pose.
  Support guided_refine(const ModelIndex& index, const Params& params, const ModelInfo& info,
                        const FrameKeypoints& frame, Homography& h);
  // Removes the matches touching the inlier pairs (pair_inlier_) of the
  // cluster just judged and marks those pairs explained.
  void explain_cluster(int k);
  // The distinct scene keypoints among the inlier pairs (pair_inlier_).
  int distinct_inlier_points();
  // Distinct keypoint correspondences and, per keygraph match, its k indices into them.
  WorkVector<std::uint64_t> pairs_;
  WorkVector<Point2f> pair_model_;
  WorkVector<Point2f> pair_scene_;
  WorkVector<std::uint32_t> match_pairs_;
  WorkVector<std::uint8_t> pair_inlier_;
  WorkVector<std::uint8_t> pair_dead_;  // explained by an instance already found
  WorkVector<std::uint8_t> match_active_;
  WorkVector<int> pair_votes_;            // matches that imply each pair
  WorkVector<int> match_quality_;         // per match: other matches sharing its pairs
  WorkVector<int> active_;                // indices of matches still in play
  WorkVector<LocalAffine> match_affine_;  // per match: its pre-test map (two-match samples)

  WorkVector<Point2f> inlier_model_;
  WorkVector<Point2f> inlier_scene_;
  WorkVector<Point2f> guided_model_;
  WorkVector<Point2f> guided_scene_;
  AppearanceAligner aligner_;
  int barren_draws_ = 0;
  double align_min_ncc_ = -1.0, align_coarse_min_ncc_ = -1.0;
  AlignCounts align_counts_;
};

}  // namespace kg
