// The frame's pipeline (paper sections 5-7; docs/ARCHITECTURE.md): the
// stages a Detector runs on each frame, in the paper's order, each a unit
// with its buffers reserved here, at construction, from the Limits:
//
//   keypoints     core/keypoints/hessian.h          (or the caller's)
//   sampling      core/sampling/sampling.h
//   keygraphs     core/keygraphs/delaunay.h, keygraph.h
//   description   core/description/scene_arcs.h
//   selection     core/selection/selection.h, triangle_check.h
//   pose          core/pose/pose.h
//
// run() in frame_pipeline.cpp reads top to bottom as that list; the 2x
// upsampled frames of KeypointParams::scene_upsample wrap it
// (scene_upsample.cpp). Nothing here allocates after construction.
#pragma once

#include <chrono>
#include <cstdint>

#include "core/description/scene_arcs.h"
#include "core/image/plane.h"
#include "core/index/arc_search.h"
#include "core/keygraphs/delaunay.h"
#include "core/keygraphs/keygraph.h"
#include "core/keypoints/hessian.h"
#include "core/pose/point_grid.h"
#include "core/pose/pose_stage.h"
#include "core/sampling/sampling.h"
#include "core/selection/arc_adjacency.h"
#include "core/selection/selection.h"
#include "core/support/worker_pool.h"
#include "core/support/workspace.h"
#include "keygraph/detector.h"

namespace kg {

// keypoints.scene_upsample 4 upsamples a window of this many frame pixels a
// side (scene_upsample.cpp), never the whole frame.
inline constexpr int kUpsampleWindow = 112;

class FramePipeline {
 public:
  using Clock = std::chrono::steady_clock;

  // Reserves every buffer from `memory` for `limits` (the caller's; the
  // pipeline doubles the frame size for upsampled frames). With fill ==
  // false only reserves (Detector::workspace_bytes' measuring pass, whose
  // memory is a placeholder): nothing is written. `options` must have passed
  // check_options().
  FramePipeline(const ModelIndex& index, const Limits& limits, const DetectOptions& options,
                std::pmr::memory_resource* memory, bool fill);

  // Whether `options` can be used with `index`: every value in range and
  // every model id in the index.
  static Status check_options(const ModelIndex& index, const DetectOptions& options);
  // Uses `options` (checked) from the next frame on.
  void set_options(const DetectOptions& options);
  const DetectOptions& options() const { return options_; }
  bool searches_model(int id) const;

  // The Detector's detect() overloads: the frame checked against the
  // limits, keypoints from the Hessian (keypoints == nullptr and count < 0)
  // or the caller's.
  Status detect(ImageView frame, DetectionList& out);
  Status detect(ImageView frame, const Keypoint* keypoints, int count,
                const std::uint8_t* vertex_descriptors, DetectionList& out);

  const DetectStats& stats() const { return stats_; }
  const WorkVector<KeygraphMatch>& matches() const { return matches_; }
  const WorkVector<Keypoint>& scene_keypoints() const { return scene_keypoints_; }

 private:
  // The stages, in order (frame_pipeline.cpp).
  Status run(ImageView frame, const Keypoint* keypoints, int count, const std::uint8_t* descriptors,
             DetectionList& out, Clock::time_point start);
  Status detect_keypoints_and_run(ImageView frame, DetectionList& out);
  void keep_strongest(const Keypoint* keypoints, int count, const std::uint8_t* descriptors);
  void sample(const Keypoint* keypoints, int count, const std::uint8_t* descriptors);
  void build_keygraphs();
  // blur false: the frame was blurred already (run()).
  void describe_arcs(ImageView frame, bool blur);
  void select_correspondences();
  void estimate_poses(ImageView frame, const Keypoint* keypoints, int count, DetectionList& out);
  void apply_confidence_floor(DetectionList& out) const;
  // DetectOptions::time_budget_ms: starts the frame's clock; then whether
  // it ran out (recording the stage in the stats the first time).
  void start_budget();
  bool out_of_time(const char* stage);

  // Upsampled frames (scene_upsample.cpp).
  int upsample_mode() const { return params_.keypoints.scene_upsample; }
  bool upsampling() const { return upsample_mode() >= 2; }
  ImageView work_frame(ImageView frame);
  void upsample_keypoints(const Keypoint*& keypoints, int& count, const std::uint8_t*& descriptors);
  void map_to_frame(DetectionList& out);
  void merge(const DetectionList& more, DetectionList& out);
  // scene_upsample 3: drops from `up` the detections that overlap none of
  // the frame pass's (`frame_found`) and fall below
  // DetectOptions::upsampled_min_confidence.
  void drop_weak_upsampled_only(const DetectionList& frame_found, DetectionList& up) const;
  // scene_upsample 4: after the frame's pass, the frame upsampled 2x around
  // the densest cluster of correspondences of models left without a pose.
  Status upsample_where_it_pays(ImageView frame, DetectionList& out);

  const ModelIndex* index_;
  Limits caller_limits_;  // the Detector's: the frames it accepts
  Limits limits_;         // of the frames worked on: the upsampled frame's with scene_upsample 2, 3
  Params params_;         // the index's, with options_ applied
  DetectOptions options_;
  DetectStats stats_;
  Clock::time_point deadline_{};
  bool budgeted_ = false;
  WorkerPool workers_;  // Limits::threads, started with the pipeline
  ArcSearch search_;
  WorkVector<std::uint8_t> model_searched_;  // per model: 1 when searched
  bool filter_models_ = false;               // DetectOptions::models was given
  // scene_upsample 3: the upsampled pass is running (its sampled keypoints
  // are cut to DetectOptions::upsampled_scene_keypoints).
  bool second_pass_ = false;

  Plane<std::uint8_t> upsampled_;  // the frame, with scene_upsample 2 or 3
  DetectionList upsampled_found_;  // the upsampled pass's, with scene_upsample 3
  HessianDetector hessian_;
  WorkVector<Keypoint> detected_;
  // Vertex descriptors: of the model keypoints' inverse norms (once), of the
  // strongest keypoints when the input is cut to max_keypoints, and of the
  // sampled keypoints.
  WorkVector<float> model_inverse_norms_;
  WorkVector<int> order_;
  WorkVector<std::uint8_t> detected_descriptors_;
  WorkVector<std::uint8_t> scene_descriptors_;
  WorkVector<float> scene_inverse_norms_;
  SeparatedSampler sampler_;
  WorkVector<int> selected_;
  WorkVector<Keypoint> scene_keypoints_;
  WorkVector<Point2f> scene_points_;
  WorkVector<float> scene_scales_;
  Delaunay triangulation_;
  WorkVector<SceneKeygraph> keygraphs_;
  SceneArcs arcs_;
  Selector selector_;
  ArcAdjacency adjacency_;             // filled with graph.complete_circuits only
  WorkVector<KeygraphMatch> matches_;  // in selection order
  PoseStage poses_;
  PointGrid grid_;
};

}  // namespace kg
