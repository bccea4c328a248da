#include "core/pipeline/frame_pipeline.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/description/vertex_descriptor.h"
#include "core/index/index_format.h"
#include "core/pose/confidence.h"
#include "core/selection/triangle_check.h"
#include "core/support/log.h"
#include "core/support/rng.h"
#include "core/support/strongest.h"

namespace kg {

namespace {

double ms_since(FramePipeline::Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(FramePipeline::Clock::now() - t).count();
}

constexpr auto kRow = static_cast<std::size_t>(kVertexDescriptorSize);
// Extremum candidates kept per Hessian scale level, per output keypoint.
constexpr int kCandidatesPerKeypoint = 16;

// The index's parameters with the runtime options in place.
Params with_options(const Params& index_params, const DetectOptions& options) {
  Params p = index_params;
  p.ransac = options.ransac;
  p.descriptor.max_search_leaves = options.max_search_leaves;
  p.descriptor.search_reference_models = options.search_reference_models;
  return p;
}

// The limits the scene side works within: the caller's, for frames upsampled
// 2x when KeypointParams::scene_upsample asks for it (2 or 3), and for the
// frame or its upsampled window, whichever is larger, with 4.
Limits work_limits(const Limits& l, const Params& params) {
  const int mode = params.keypoints.scene_upsample;
  if (mode == 4) {
    const int window = 2 * kUpsampleWindow;
    return l.for_frame(std::max(l.max_width, window), std::max(l.max_height, window));
  }
  const int f = mode >= 2 ? 2 : 1;
  return l.for_frame(f * l.max_width, f * l.max_height);
}

std::uint32_t largest_model(const ModelIndex& index) {
  std::uint32_t most = 0;
  for (int m = 0; m < index.model_count(); ++m)
    most = std::max(most, index.model(m).keypoint_count);
  return most;
}

// graph.complete_circuits applies to 3-circuits.
bool completes_circuits(const Params& params) {
  return params.graph.complete_circuits != 0 && params.graph.structure == Structure::kCircuit3;
}

// Orders keypoints strongest first, ties by input position.
struct Stronger {
  const Keypoint* keypoints;
  bool operator()(int a, int b) const {
    return keypoints[a].response > keypoints[b].response ||
           (keypoints[a].response == keypoints[b].response && a < b);
  }
};

Status check_frame(ImageView frame, const Limits& limits) {
  if (frame.empty() || frame.stride < frame.width)
    return {StatusCode::kInvalidArgument, "empty or malformed frame"};
  if (frame.width > limits.max_width || frame.height > limits.max_height)
    return {StatusCode::kInvalidArgument,
            "frame " + std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                " is larger than the detector's limits (" + std::to_string(limits.max_width) + "x" +
                std::to_string(limits.max_height) + ": Limits::for_frame)"};
  return Status::ok();
}

bool wants_vertex_descriptors(const Params& params) {
  return params.descriptor.vertex_descriptor != VertexDescriptor::kNone;
}

Status missing_vertex_descriptors() {
  return {StatusCode::kInvalidArgument,
          "index was built with SIFT vertex descriptors, which the core cannot compute: pass "
          "keypoints with their descriptors (DesktopDetector does)"};
}

}  // namespace

FramePipeline::FramePipeline(const ModelIndex& index, const Limits& limits,
                             const DetectOptions& options, std::pmr::memory_resource* memory,
                             bool fill)
    : index_(&index),
      caller_limits_(limits),
      limits_(work_limits(limits, index.params())),
      params_(with_options(index.params(), options)),
      options_(options),
      // The measuring pass starts no threads.
      workers_(fill ? limits.threads : 1),
      search_(index, ArcSearch::leaves_for(params_.descriptor,
                                           static_cast<std::uint64_t>(index.model_count()))),
      model_searched_(memory),
      upsampled_(memory),
      hessian_(memory),
      detected_(memory),
      model_inverse_norms_(memory),
      order_(memory),
      detected_descriptors_(memory),
      scene_descriptors_(memory),
      scene_inverse_norms_(memory),
      sampler_(memory),
      selected_(memory),
      scene_keypoints_(memory),
      scene_points_(memory),
      scene_scales_(memory),
      triangulation_(memory),
      keygraphs_(memory),
      arcs_(memory),
      selector_(memory),
      adjacency_(memory),
      matches_(memory),
      poses_(memory),
      grid_(memory) {
  const Params& params = params_;
  const Limits& l = limits_;
  const auto frame_keypoints = static_cast<std::size_t>(l.max_keypoints);
  const auto scene = static_cast<std::size_t>(l.max_scene_keypoints);
  const auto correspondences = static_cast<std::size_t>(l.max_correspondences);
  model_searched_.reserve(static_cast<std::size_t>(index.model_count()));
  if (fill) set_options(options);
  if (upsample_mode() == 4) {
    upsampled_.reserve(2 * kUpsampleWindow, 2 * kUpsampleWindow);
  } else if (upsampling()) {
    upsampled_.reserve(l.max_width, l.max_height);
  }
  hessian_.reserve(l.max_width, l.max_height, params.keypoints, l.max_keypoints,
                   kCandidatesPerKeypoint * l.max_keypoints, l.threads);
  if (workers_.threads() > 1) hessian_.set_workers(&workers_);
  detected_.reserve(frame_keypoints);
  sampler_.reserve(l.max_keypoints, l.max_width, l.max_height, params.graph.scene_sample_distance);
  selected_.reserve(frame_keypoints);  // the sampler's output, cut afterwards
  scene_keypoints_.reserve(scene);
  scene_points_.reserve(scene);
  scene_scales_.reserve(scene);
  triangulation_.reserve(l.max_scene_keypoints);
  keygraphs_.reserve(3 * scene);  // edges, faces (2n) or internal edges (3n)
  arcs_.reserve(l.max_width, l.max_height, l.max_scene_keypoints, params.descriptor.blur_sigma,
                l.threads, fill);
  if (workers_.threads() > 1) arcs_.set_workers(&workers_);
  selector_.reserve(l, index, completes_circuits(params), fill);
  if (completes_circuits(params)) adjacency_.build(index, fill);
  matches_.reserve(correspondences);
  poses_.reserve(l.threads, l.max_correspondences, vertex_count(params.graph.structure),
                 largest_model(index), index.max_appearance_pixels(), index.model_count(), fill);
  grid_.reserve(l.max_keypoints, l.max_width, l.max_height,
                std::max(4.f, static_cast<float>(params.ransac.inlier_threshold)));
  if (const std::uint8_t* v = index.vertex_descriptors()) {
    model_inverse_norms_.reserve(index.keypoint_count());
    for (std::uint32_t i = 0; fill && i < index.keypoint_count(); ++i)
      model_inverse_norms_.push_back(vertex_inverse_norm(v + i * kRow));
    order_.reserve(frame_keypoints);
    detected_descriptors_.reserve(frame_keypoints * kRow);
    scene_descriptors_.reserve(scene * kRow);
    scene_inverse_norms_.reserve(scene);
  }
}

Status FramePipeline::check_options(const ModelIndex& index, const DetectOptions& options) {
  if (Status s = format::validate_params(with_options(index.params(), options)); !s)
    return {StatusCode::kInvalidArgument, "detect options: " + s.message()};
  if (!(options.min_confidence >= 0.0 && options.min_confidence <= 1.0))
    return {StatusCode::kInvalidArgument, "detect options: min_confidence must be in [0, 1]"};
  if (!(options.time_budget_ms >= 0.0 && std::isfinite(options.time_budget_ms)))
    return {StatusCode::kInvalidArgument,
            "detect options: time_budget_ms must be a finite number >= 0 (0: no budget)"};
  if (!(options.search_arcs_per_leaf >= 0 && options.search_arcs_per_leaf <= kLeafSize))
    return {StatusCode::kInvalidArgument, "detect options: search_arcs_per_leaf must be in [0, " +
                                              std::to_string(kLeafSize) + "] (0: every arc found)"};
  if (!(options.ransac_barren_draws >= 0))
    return {StatusCode::kInvalidArgument,
            "detect options: ransac_barren_draws must be >= 0 (0: never stop early)"};
  if (!(options.align_coarse_min_ncc >= -1.0 && options.align_coarse_min_ncc <= 1.0))
    return {StatusCode::kInvalidArgument,
            "detect options: align_coarse_min_ncc must be in [-1, 1] (-1: never)"};
  if (!(options.align_min_ncc >= -1.0 && options.align_min_ncc <= 1.0))
    return {StatusCode::kInvalidArgument,
            "detect options: align_min_ncc must be in [-1, 1] (-1: never)"};
  if (!(options.upsampled_min_confidence >= 0.0 && options.upsampled_min_confidence <= 1.0))
    return {StatusCode::kInvalidArgument,
            "detect options: upsampled_min_confidence must be in [0, 1]"};
  if (!(options.upsampled_scene_keypoints >= 0))
    return {StatusCode::kInvalidArgument,
            "detect options: upsampled_scene_keypoints must be >= 0 (0: "
            "Limits::max_scene_keypoints)"};
  if (options.models == nullptr && options.model_count > 0)
    return {StatusCode::kInvalidArgument, "detect options: model_count without models"};
  for (std::size_t i = 0; options.models != nullptr && i < options.model_count; ++i) {
    if (options.models[i] < 0 || options.models[i] >= index.model_count())
      return {StatusCode::kInvalidArgument,
              "detect options: model id " + std::to_string(options.models[i]) +
                  " is not in the index (" + std::to_string(index.model_count()) + " models)"};
  }
  return Status::ok();
}

void FramePipeline::set_options(const DetectOptions& options) {
  options_ = options;
  options_.models = nullptr;
  options_.model_count = 0;
  params_ = with_options(index_->params(), options);
  search_.set_max_leaves(
      ArcSearch::leaves_for(params_.descriptor, static_cast<std::uint64_t>(index_->model_count())));
  search_.set_max_hits(static_cast<std::uint32_t>(search_.max_leaves()) *
                       static_cast<std::uint32_t>(std::max(0, options.search_arcs_per_leaf)));
  const auto models = static_cast<std::size_t>(index_->model_count());
  filter_models_ = options.models != nullptr;
  model_searched_.assign(models, filter_models_ ? 0 : 1);
  for (std::size_t i = 0; options.models != nullptr && i < options.model_count; ++i)
    model_searched_[static_cast<std::size_t>(options.models[i])] = 1;
}

bool FramePipeline::searches_model(int id) const {
  return id >= 0 && static_cast<std::size_t>(id) < model_searched_.size() &&
         model_searched_[static_cast<std::size_t>(id)] != 0;
}

void FramePipeline::start_budget() {
  budgeted_ = options_.time_budget_ms > 0.0;
  if (budgeted_)
    deadline_ =
        Clock::now() +
        std::chrono::duration_cast<Clock::duration>(
            std::chrono::duration<double, std::milli>(std::min(options_.time_budget_ms, 1e9)));
}

bool FramePipeline::out_of_time(const char* stage) {
  if (stats_.stopped_early != nullptr) return true;
  if (!budgeted_ || Clock::now() <= deadline_) return false;
  stats_.stopped_early = stage;
  return true;
}

Status FramePipeline::detect(ImageView frame, DetectionList& out) {
  out.clear();
  stats_ = DetectStats{};
  start_budget();
  if (Status s = check_frame(frame, caller_limits_); !s) return s;
  if (wants_vertex_descriptors(params_)) return missing_vertex_descriptors();
  if (params_.keypoints.detector != KeypointDetector::kHessian)
    return {
        StatusCode::kInvalidArgument,
        "index was built with a keypoint detector the core does not have (MSER): pass keypoints"};
  const int mode = upsample_mode();
  Status s = Status::ok();
  if (mode != 2) s = detect_keypoints_and_run(frame, out);
  if (mode == 4 && s && !out_of_time("keypoints")) {
    s = upsample_where_it_pays(frame, out);
  } else if (mode >= 2 && mode != 4 && s && !out_of_time("keypoints")) {
    DetectionList& up = mode == 3 ? upsampled_found_ : out;
    up.clear();
    second_pass_ = mode == 3;
    s = detect_keypoints_and_run(work_frame(frame), up);
    second_pass_ = false;
    map_to_frame(up);
    if (mode == 3) {
      drop_weak_upsampled_only(out, up);
      merge(up, out);
    }
  }
  apply_confidence_floor(out);
  return s;
}

Status FramePipeline::detect(ImageView frame, const Keypoint* keypoints, int count,
                             const std::uint8_t* vertex_descriptors, DetectionList& out) {
  out.clear();
  stats_ = DetectStats{};
  start_budget();
  if (Status s = check_frame(frame, caller_limits_); !s) return s;
  if (count < 0 || (count > 0 && keypoints == nullptr))
    return {StatusCode::kInvalidArgument, "bad keypoint array"};
  if (!wants_vertex_descriptors(params_)) {
    vertex_descriptors = nullptr;
  } else if (vertex_descriptors == nullptr && count > 0) {
    return missing_vertex_descriptors();
  }
  const int mode = upsample_mode();
  if (mode != 2) {
    Status s = run(frame, keypoints, count, vertex_descriptors, out, Clock::now());
    if (mode == 1 || mode == 4 || !s) {  // 4: no second pass for keypoints passed in
      apply_confidence_floor(out);
      return s;
    }
  }
  const auto start = Clock::now();
  const ImageView work = work_frame(frame);
  const int given = count;
  upsample_keypoints(keypoints, count, vertex_descriptors);
  const bool truncated = count < given;
  DetectionList& up = mode == 3 ? upsampled_found_ : out;
  up.clear();
  second_pass_ = mode == 3;
  const Status s = run(work, keypoints, count, vertex_descriptors, up, start);
  second_pass_ = false;
  stats_.keypoints = given;
  stats_.truncated_keypoints |= truncated;
  map_to_frame(up);
  if (mode == 3) {
    drop_weak_upsampled_only(out, up);
    merge(up, out);
  }
  apply_confidence_floor(out);
  return s;
}

Status FramePipeline::detect_keypoints_and_run(ImageView frame, DetectionList& out) {
  const auto start = Clock::now();
  if (!hessian_.detect(frame, params_.keypoints, limits_.max_keypoints, detected_))
    stats_.truncated_keypoints = true;
  stats_.ms_keypoints += ms_since(start);
  return run(frame, detected_.data(), static_cast<int>(detected_.size()), nullptr, out,
             Clock::now());
}

// The frame's stages, in the paper's order (section numbers of the paper;
// step numbers of docs/ARCHITECTURE.md).
Status FramePipeline::run(ImageView frame, const Keypoint* keypoints, int count,
                          const std::uint8_t* descriptors, DetectionList& out,
                          Clock::time_point start) {
  // 5. Keypoints: at most max_keypoints, the strongest (callers pass them
  // in any order).
  stats_.keypoints = count;
  if (count > limits_.max_keypoints) {
    stats_.truncated_keypoints = true;
    keep_strongest(keypoints, count, descriptors);
    keypoints = detected_.data();
    if (descriptors != nullptr) descriptors = detected_descriptors_.data();
    count = limits_.max_keypoints;
  }
  if (out_of_time("keypoints")) return Status::ok();
  const auto graph = [&] {
    // 5. Sampling: a maximal subset, no two closer than scene_sample_distance.
    sample(keypoints, count, descriptors);
    // 6. Scene keygraphs from the Delaunay triangulation of the sample.
    build_keygraphs();
  };
  // The frame blurred for the arc descriptors (7) does not depend on the
  // graph: with workers, one thread blurs while the other builds the graph
  // (each writes its own members), and ms_graph holds both.
  const bool blur_beside = workers_.threads() > 1;
  if (blur_beside) {
    auto task = [&](int i, int) {
      if (i == 0) {
        graph();
      } else {
        arcs_.blur(frame, params_.descriptor);
      }
    };
    workers_.run(2, task);
  } else {
    graph();
  }
  stats_.ms_graph = ms_since(start);
  if (out_of_time("keygraphs")) return Status::ok();
  // 7. Arc descriptors, on the frame blurred once.
  describe_arcs(frame, !blur_beside);
  if (out_of_time("description")) return Status::ok();
  // 8. Keygraph correspondences through keytuples, then the triangle check.
  select_correspondences();
  if (out_of_time("selection")) return Status::ok();
  // 9. Pose per model: RANSAC over its keygraph correspondences.
  estimate_poses(frame, keypoints, count, out);
  if (stats_.truncated_keypoints || stats_.truncated_arc_matches ||
      stats_.truncated_correspondences || stats_.truncated_detections)
    KG_LOG("limits reached: keypoints %d, arc matches %d, correspondences %d, detections %d",
           stats_.truncated_keypoints, stats_.truncated_arc_matches,
           stats_.truncated_correspondences, stats_.truncated_detections);
  return Status::ok();
}

void FramePipeline::keep_strongest(const Keypoint* keypoints, int count,
                                   const std::uint8_t* descriptors) {
  // A heap of indices (its front the weakest kept), then strongest first.
  const Stronger stronger{keypoints};
  const int keep = limits_.max_keypoints;
  order_.clear();
  WorkVector<int>& heap = descriptors != nullptr ? order_ : selected_;
  heap.clear();
  for (int i = 0; i < count; ++i)
    offer_strongest(heap, i, static_cast<std::size_t>(std::max(0, keep)), stronger);
  std::sort_heap(heap.begin(), heap.end(), stronger);
  detected_.clear();
  for (int i : heap) detected_.push_back(keypoints[i]);
  if (descriptors != nullptr) {
    detected_descriptors_.resize(heap.size() * kRow);
    for (std::size_t i = 0; i < heap.size(); ++i)
      std::copy_n(descriptors + static_cast<std::size_t>(heap[i]) * kRow, kRow,
                  detected_descriptors_.data() + i * kRow);
  }
}

void FramePipeline::sample(const Keypoint* keypoints, int count, const std::uint8_t* descriptors) {
  Rng rng(params_.ransac.seed);
  sampler_.sample(keypoints, count, params_.graph.scene_sample_distance,
                  params_.graph.scene_sampling == SceneSampling::kRandom ? &rng : nullptr,
                  selected_);
  if (static_cast<int>(selected_.size()) > limits_.max_scene_keypoints) {
    stats_.truncated_keypoints = true;
    selected_.resize(static_cast<std::size_t>(limits_.max_scene_keypoints));
  }
  // scene_upsample 3's upsampled pass keeps fewer (the strongest: the
  // sampler visits them strongest first), by option, not as a limit.
  const int second_most = options_.upsampled_scene_keypoints;
  if (second_pass_ && second_most > 0 && static_cast<int>(selected_.size()) > second_most)
    selected_.resize(static_cast<std::size_t>(second_most));
  scene_keypoints_.clear();
  scene_points_.clear();
  scene_scales_.clear();
  for (int i : selected_) {
    scene_keypoints_.push_back(keypoints[i]);
    scene_points_.push_back({keypoints[i].x, keypoints[i].y});
    scene_scales_.push_back(keypoints[i].scale);
  }
  stats_.sampled_keypoints = static_cast<int>(scene_points_.size());
  if (descriptors == nullptr) return;
  scene_descriptors_.resize(selected_.size() * kRow);
  scene_inverse_norms_.resize(selected_.size());
  for (std::size_t i = 0; i < selected_.size(); ++i) {
    std::uint8_t* row = scene_descriptors_.data() + i * kRow;
    std::copy_n(descriptors + static_cast<std::size_t>(selected_[i]) * kRow, kRow, row);
    scene_inverse_norms_[i] = vertex_inverse_norm(row);
  }
}

void FramePipeline::build_keygraphs() {
  triangulation_.triangulate(scene_points_.data(), static_cast<int>(scene_points_.size()));
  scene_keygraphs(triangulation_, scene_points_.data(), params_.graph.structure, keygraphs_);
  stats_.keygraphs = static_cast<int>(keygraphs_.size());
}

void FramePipeline::describe_arcs(ImageView frame, bool blur) {
  const auto start = Clock::now();
  if (blur) arcs_.blur(frame, params_.descriptor);
  // The arcs the selection looks up: every arc of a circuit, the one arc of
  // an arc keygraph.
  const Structure structure = params_.graph.structure;
  const int arcs_per_keygraph = structure == Structure::kArc ? 1 : vertex_count(structure);
  arcs_.describe(search_, params_, scene_points_.data(), scene_scales_.data(), triangulation_,
                 keygraphs_, arcs_per_keygraph);
  stats_.ms_describe = ms_since(start);
}

void FramePipeline::select_correspondences() {
  const auto start = Clock::now();
  SelectionInput in;
  in.index = index_;
  in.params = &params_;
  in.search = &search_;
  in.scene_points = scene_points_.data();
  in.triangulation = &triangulation_;
  in.keygraphs = &keygraphs_;
  in.arcs = &arcs_;
  if (filter_models_) in.model_searched = model_searched_.data();
  if (!scene_descriptors_.empty()) {
    in.model_descriptors = index_->vertex_descriptors();
    in.model_inverse_norms = model_inverse_norms_.data();
    in.scene_descriptors = scene_descriptors_.data();
    in.scene_inverse_norms = scene_inverse_norms_.data();
  }
  if (completes_circuits(params_)) in.adjacency = &adjacency_;
  if (workers_.threads() > 1) in.workers = &workers_;
  if (budgeted_) in.deadline = &deadline_;
  selector_.select(in, limits_, matches_, stats_);
  if (selector_.ran_out_of_time() && stats_.stopped_early == nullptr)
    stats_.stopped_early = "selection";
  stats_.arcs_described = arcs_.described_count();
  stats_.patch_rejections =
      check_triangle_patches(*index_, params_, arcs_.blurred(), scene_points_.data(), matches_,
                             workers_.threads() > 1 ? &workers_ : nullptr);
  stats_.ms_select = ms_since(start);
}

void FramePipeline::estimate_poses(ImageView frame, const Keypoint* keypoints, int count,
                                   DetectionList& out) {
  const auto start = Clock::now();
  FrameKeypoints frame_keypoints;
  frame_keypoints.keypoints = keypoints;
  frame_keypoints.count = count;
  frame_keypoints.width = frame.width;
  frame_keypoints.height = frame.height;
  frame_keypoints.image = arcs_.blurred();
  const float cell = std::max(4.f, static_cast<float>(params_.ransac.inlier_threshold));
  if (!matches_.empty()) grid_.build(keypoints, count, frame.width, frame.height, cell);
  frame_keypoints.grid = &grid_;
  // Each model's RANSAC, on the workers when there are several.
  poses_.set_barren_draws(options_.ransac_barren_draws);
  poses_.set_align_min_ncc(options_.align_min_ncc, options_.align_coarse_min_ncc);
  const PoseStage::Result r = poses_.estimate(
      *index_, params_, matches_.data(), matches_.size(), scene_points_.data(), frame_keypoints,
      limits_.max_detections, workers_.threads() > 1 ? &workers_ : nullptr,
      budgeted_ ? &deadline_ : nullptr, out);
  stats_.ransac_iterations += r.ransac_iterations;
  stats_.alignments += r.alignments;
  stats_.alignments_abandoned += r.alignments_abandoned;
  stats_.truncated_detections = stats_.truncated_detections || r.truncated;
  if (r.out_of_time) out_of_time("pose");
  keep_best_of_overlapping(out);
  stats_.ms_pose = ms_since(start);
}

void FramePipeline::apply_confidence_floor(DetectionList& out) const {
  if (!(options_.min_confidence > 0.0)) return;
  std::size_t kept = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (out[i].confidence >= options_.min_confidence) out[kept++] = out[i];
  }
  out.truncate(kept);
}

}  // namespace kg
