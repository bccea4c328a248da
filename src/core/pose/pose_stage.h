// The frame's pose stage (paper section 7): the keygraph correspondences
// grouped by model, and each model's RANSAC (core/pose/pose.h) run on its
// own, so that the models can be spread over a Detector's workers. Each
// model's random stream is seeded from its id and a pose only compares
// itself with earlier instances of its own model, so a model's instances do
// not depend on the others: each thread appends them to its own list, and
// the lists are concatenated in model order, which is what one thread gives.
// Where one thread would have reached max_detections (and stopped that
// model's attempts early) the models are estimated again in order on the
// caller's thread: the output is the same for any thread count, byte for
// byte, stats included. The appearance alignments sample the frame on the
// threads left idle (AppearanceAligner::set_workers, a nested run of the
// pool), which changes nothing in their results. Nothing is allocated after
// reserve().
#pragma once

#include <chrono>
#include <cstdint>

#include "core/pose/pose.h"
#include "core/support/worker_pool.h"
#include "core/support/workspace.h"
#include "keygraph/detector.h"
#include "keygraph/model_index.h"

namespace kg {

class PoseStage {
 public:
  using Clock = std::chrono::steady_clock;

  explicit PoseStage(std::pmr::memory_resource* memory = std::pmr::get_default_resource());

  // Sizes everything for `threads` threads (Limits::threads), up to
  // max_matches correspondences of k vertices, `models` models of up to
  // max_model_keypoints keypoints and appearances of up to
  // max_appearance_pixels. With fill false (Detector::workspace_bytes'
  // measuring pass) nothing is written into the memory.
  void reserve(int threads, int max_matches, int k, std::uint32_t max_model_keypoints,
               int max_appearance_pixels, int models, bool fill);

  // DetectOptions::ransac_barren_draws for the estimations that follow.
  void set_barren_draws(int draws) { barren_draws_ = draws; }
  // DetectOptions::align_min_ncc and align_coarse_min_ncc for the
  // estimations that follow.
  void set_align_min_ncc(double before, double coarse) {
    align_min_ncc_ = before;
    align_coarse_min_ncc_ = coarse;
  }

  struct Result {
    int ransac_iterations = 0;
    int alignments = 0, alignments_abandoned = 0;  // DetectStats'
    bool truncated = false;                        // max_out reached
    bool out_of_time = false;  // `deadline` passed before every model was estimated
  };
  // Appends the instances found among matches[0..n) (any order of models)
  // to `out`, at most max_out in all, model by model in id order; with
  // `workers`, the models run on them. `deadline` (nullptr: none) is
  // checked before each model.
  Result estimate(const ModelIndex& index, const Params& params, const KeygraphMatch* matches,
                  std::size_t n, const Point2f* scene_points, const FrameKeypoints& frame,
                  int max_out, WorkerPool* workers, const Clock::time_point* deadline,
                  DetectionList& out);

 private:
  // One model's share of the frame: its correspondences grouped_[begin,
  // end), and where its instances went (the list of `worker`, [first,
  // last)).
  struct Task {
    int model = 0;
    std::uint32_t begin = 0, end = 0;
    int worker = 0;
    std::uint32_t first = 0, last = 0;
    int iterations = 0;
    int alignments = 0, abandoned = 0;
    bool truncated = false;  // its thread's list was full
    bool skipped = false;    // out of time before it started
  };
  void group(const ModelIndex& index, const KeygraphMatch* matches, std::size_t n);
  // The models one after another into `out`, as one thread does; the
  // appearance alignments sample the frame on `workers` (nullptr: none).
  Result estimate_in_order(const ModelIndex& index, const Params& params,
                           const Point2f* scene_points, const FrameKeypoints& frame, int max_out,
                           WorkerPool* workers, const Clock::time_point* deadline,
                           DetectionList& out);

  std::pmr::memory_resource* memory_;
  WorkVector<KeygraphMatch> grouped_;      // the correspondences grouped by model (stable)
  WorkVector<std::uint32_t> model_begin_;  // per model, then one past the last
  WorkVector<Task> tasks_;                 // the models with correspondences, largest first
  // Per thread (the caller's first): an estimator and, with several
  // threads, its instances (tasks_ and found_ are empty with one).
  WorkVector<PoseEstimator> estimators_;
  WorkVector<DetectionList> found_;
  int barren_draws_ = 0;
  double align_min_ncc_ = -1.0, align_coarse_min_ncc_ = -1.0;
};

}  // namespace kg
