#include "keygraph/detector.h"

#include <algorithm>
#include <chrono>
#include <new>
#include <string>
#include <utility>

#include "core/description/vertex_descriptor.h"
#include "core/image/blur.h"
#include "core/image/plane.h"
#include "core/image/upsample.h"
#include "core/index/kdtree.h"
#include "core/keygraphs/delaunay.h"
#include "core/keygraphs/keygraph.h"
#include "core/keypoints/hessian.h"
#include "core/pose/confidence.h"
#include "core/pose/pose.h"
#include "core/sampling/sampling.h"
#include "core/selection/selection.h"
#include "core/selection/triangle_patch.h"
#include "core/support/log.h"
#include "core/support/rng.h"
#include "core/support/strongest.h"
#include "core/support/workspace.h"

namespace kg {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

constexpr auto kRow = static_cast<std::size_t>(kVertexDescriptorSize);
// Extremum candidates kept per Hessian scale level, per output keypoint.
constexpr int kCandidatesPerKeypoint = 16;

bool wants_vertex_descriptors(const ModelIndex& index) {
  return index.params().descriptor.vertex_descriptor != VertexDescriptor::kNone;
}

Status missing_vertex_descriptors() {
  return {StatusCode::kInvalidArgument,
          "index was built with SIFT vertex descriptors, which the core cannot compute: pass "
          "keypoints with their descriptors (DesktopDetector does)"};
}

Status check_limits(const Limits& l) {
  const bool ok = l.max_width >= 1 && l.max_height >= 1 && l.max_width <= Limits::kMaxSide &&
                  l.max_height <= Limits::kMaxSide && l.max_keypoints >= 1 &&
                  l.max_scene_keypoints >= 1 && l.max_arc_matches >= 1 && l.max_arc_pool >= 1 &&
                  l.max_correspondences >= 1 && l.max_detections >= 1 &&
                  l.max_detections <= kMaxDetections;
  if (ok) return Status::ok();
  return {StatusCode::kInvalidArgument,
          "detector limits out of range (frame 1..16384 px a side, every count >= 1, "
          "max_detections <= " +
              std::to_string(kMaxDetections) + ")"};
}

// The limits the scene side works within: the caller's, for frames upsampled
// 2x when KeypointParams::scene_upsample asks for it (2 or 3).
Limits work_limits(const Limits& l, const Params& params) {
  const int f = params.keypoints.scene_upsample >= 2 ? 2 : 1;
  return l.for_frame(f * l.max_width, f * l.max_height);
}

// check_limits(), and the upsampled frame within the largest side too (a
// larger one would ask for a workspace of gigabytes).
Status check_limits(const Limits& l, const Params& params) {
  if (Status s = check_limits(l); !s) return s;
  const Limits work = work_limits(l, params);
  if (work.max_width <= Limits::kMaxSide && work.max_height <= Limits::kMaxSide)
    return Status::ok();
  return {StatusCode::kInvalidArgument,
          "detector limits out of range: with keypoints.scene_upsample 2 or 3 the frame is "
          "upsampled 2x, so at most " +
              std::to_string(Limits::kMaxSide / 2) + " px a side"};
}

std::uint32_t largest_model(const ModelIndex& index) {
  std::uint32_t most = 0;
  for (int m = 0; m < index.model_count(); ++m)
    most = std::max(most, index.model(m).keypoint_count);
  return most;
}

// Orders keypoints strongest first, ties by input position: a heap of the
// strongest kept (its front the weakest) while scanning.
struct Stronger {
  const Keypoint* keypoints;
  bool operator()(int a, int b) const {
    return keypoints[a].response > keypoints[b].response ||
           (keypoints[a].response == keypoints[b].response && a < b);
  }
};

// graph.complete_circuits applies to 3-circuits.
bool completes_circuits(const Params& params) {
  return params.graph.complete_circuits != 0 && params.graph.structure == Structure::kCircuit3;
}

}  // namespace

struct Detector::Impl {
  // Reserves every buffer from `memory`. With fill == false only reserves
  // (the measuring pass of Detector::workspace_bytes, whose memory is a
  // placeholder): nothing is written.
  Impl(const ModelIndex& index, const Limits& limits, std::pmr::memory_resource* memory, bool fill);

  const ModelIndex* index;
  Limits limits;  // work_limits(): frame sizes of the upsampled frame
  ArcSearch search;
  DetectStats stats;

  Plane<std::uint8_t> upsampled;  // the frame, with scene_upsample 2
  HessianDetector hessian;
  WorkVector<Keypoint> detected;
  // Vertex descriptors: of the model keypoints' inverse norms (once), of the
  // strongest keypoints when the input is cut to max_keypoints, and of the
  // sampled keypoints.
  WorkVector<float> model_inverse_norms;
  WorkVector<int> order;
  WorkVector<std::uint8_t> detected_descriptors;
  WorkVector<std::uint8_t> scene_descriptors;
  WorkVector<float> scene_inverse_norms;
  Plane<std::uint8_t> blurred;
  Plane<float> blur_scratch;
  SeparatedSampler sampler;
  WorkVector<int> selected;
  WorkVector<Keypoint> scene_keypoints;
  WorkVector<Point2f> scene_points;
  WorkVector<float> scene_scales;
  Delaunay triangulation;
  WorkVector<SceneKeygraph> keygraphs;
  Selector selector;
  ArcAdjacency adjacency;             // filled with graph.complete_circuits only
  WorkVector<KeygraphMatch> matches;  // in selection order
  WorkVector<KeygraphMatch> grouped;  // the same grouped by model (stable)
  WorkVector<std::uint32_t> model_begin;
  PoseEstimator pose;
  PointGrid grid;

  // Keeps the limits.max_keypoints strongest of keypoints[0..count) (and
  // their descriptors) in `detected` (and detected_descriptors).
  void keep_strongest(const Keypoint* keypoints, int count, const std::uint8_t* descriptors);
  int mode() const { return index->params().keypoints.scene_upsample; }
  bool upsampling() const { return mode() >= 2; }
  // The frame the scene side works on: `frame`, or its upsampled copy.
  ImageView work_frame(ImageView frame);
  // The caller's keypoints in upsampled pixels, in `detected` (the strongest
  // limits.max_keypoints of them, with their descriptors).
  void upsample_keypoints(const Keypoint*& keypoints, int& count, const std::uint8_t*& descriptors);
  // Detections and sampled keypoints from upsampled to frame pixels.
  void map_to_frame(DetectionList& out);
  // The Hessian's keypoints of `frame`, then run().
  Status detect_keypoints_and_run(ImageView frame, DetectionList& out);
  // With ransac.min_triangle_correlation > 0: measures each selected
  // correspondence's triangle patch on `frame` (the blurred frame) and drops, in place and in
  // order, those that correlate below the threshold.
  void check_triangle_patches(ImageView frame);
  // scene_upsample 3: the upsampled pass's detections (frame pixels) added
  // to the frame's, then the best of overlapping ones kept.
  void merge(const DetectionList& more, DetectionList& out);
  DetectionList upsampled_found;  // the upsampled pass's, with scene_upsample 3
  Status run(ImageView frame, const Keypoint* keypoints, int count, const std::uint8_t* descriptors,
             DetectionList& out, Clock::time_point start);
};

Detector::Impl::Impl(const ModelIndex& idx, const Limits& user, std::pmr::memory_resource* memory,
                     bool fill)
    : index(&idx),
      limits(work_limits(user, idx.params())),
      search(idx),
      upsampled(memory),
      hessian(memory),
      detected(memory),
      model_inverse_norms(memory),
      order(memory),
      detected_descriptors(memory),
      scene_descriptors(memory),
      scene_inverse_norms(memory),
      blurred(memory),
      blur_scratch(memory),
      sampler(memory),
      selected(memory),
      scene_keypoints(memory),
      scene_points(memory),
      scene_scales(memory),
      triangulation(memory),
      keygraphs(memory),
      selector(memory),
      adjacency(memory),
      matches(memory),
      grouped(memory),
      model_begin(memory),
      pose(memory),
      grid(memory) {
  const Params& params = idx.params();
  const Limits& l = limits;
  if (upsampling()) upsampled.reserve(l.max_width, l.max_height);
  const auto frame_keypoints = static_cast<std::size_t>(l.max_keypoints);
  const auto scene = static_cast<std::size_t>(l.max_scene_keypoints);
  const auto correspondences = static_cast<std::size_t>(l.max_correspondences);
  hessian.reserve(l.max_width, l.max_height, params.keypoints, l.max_keypoints,
                  kCandidatesPerKeypoint * l.max_keypoints);
  detected.reserve(frame_keypoints);
  blurred.reserve(l.max_width, l.max_height);
  blur_scratch.reserve(l.max_width + 2 * blur_radius(params.descriptor.blur_sigma), 2);
  sampler.reserve(l.max_keypoints, l.max_width, l.max_height, params.graph.scene_sample_distance);
  selected.reserve(frame_keypoints);  // the sampler's output, cut afterwards
  scene_keypoints.reserve(scene);
  scene_points.reserve(scene);
  scene_scales.reserve(scene);
  triangulation.reserve(l.max_scene_keypoints);
  keygraphs.reserve(3 * scene);  // edges, faces (2n) or internal edges (3n)
  selector.reserve(l, idx.keypoint_count(), completes_circuits(params));
  if (completes_circuits(params)) adjacency.build(idx, fill);
  matches.reserve(correspondences);
  grouped.reserve(correspondences);
  model_begin.reserve(static_cast<std::size_t>(idx.model_count()) + 1);
  pose.reserve(l.max_correspondences, vertex_count(params.graph.structure), largest_model(idx),
               idx.max_appearance_pixels());
  grid.reserve(l.max_keypoints, l.max_width, l.max_height,
               std::max(4.f, static_cast<float>(params.ransac.inlier_threshold)));
  if (const std::uint8_t* v = idx.vertex_descriptors()) {
    model_inverse_norms.reserve(idx.keypoint_count());
    for (std::uint32_t i = 0; fill && i < idx.keypoint_count(); ++i)
      model_inverse_norms.push_back(vertex_inverse_norm(v + i * kRow));
    order.reserve(frame_keypoints);
    detected_descriptors.reserve(frame_keypoints * kRow);
    scene_descriptors.reserve(scene * kRow);
    scene_inverse_norms.reserve(scene);
  }
}

// What a workspace block starts with: the bump allocator over the rest of
// the block, and the detector's state, whose buffers come from it.
struct Detector::Header {
  Header(std::uint8_t* rest, std::size_t rest_size, const ModelIndex& index, const Limits& limits)
      : memory(rest, rest_size), impl(index, limits, &memory, true) {}
  Workspace memory;
  Impl impl;
};

std::size_t Detector::header_bytes() {
  return align_up(sizeof(Header), kWorkspaceAlignment);
}

std::size_t Detector::workspace_bytes(const ModelIndex& index, const Limits& limits) {
  if (!check_limits(limits, index.params())) return 0;
  // The constructor's own reserve() calls, counted: nothing is allocated.
  MeasuringResource measure;
  const Impl dry(index, limits, &measure, false);
  return header_bytes() + measure.measured();
}

Detector::Detector(const ModelIndex& index, const Limits& limits)
    : index_(&index), limits_(limits) {
  status_ = check_limits(limits, index.params());
  if (!status_) return;
  const std::size_t bytes = workspace_bytes(index, limits);
  owned_ = ::operator new (bytes, std::align_val_t{kWorkspaceAlignment});
  place(owned_, bytes);
}

Detector::Detector(const ModelIndex& index, const Limits& limits, void* buffer, std::size_t size)
    : index_(&index), limits_(limits) {
  status_ = check_limits(limits, index.params());
  if (!status_) return;
  if (buffer == nullptr || reinterpret_cast<std::uintptr_t>(buffer) % kWorkspaceAlignment != 0) {
    status_ = {StatusCode::kInvalidArgument, "detector workspace buffer must be 64-byte aligned"};
    return;
  }
  const std::size_t needed = workspace_bytes(index, limits);
  if (size < needed) {
    status_ = {StatusCode::kResourceExhausted, "detector workspace buffer of " +
                                                   std::to_string(size) + " bytes is too small (" +
                                                   std::to_string(needed) + " needed)"};
    return;
  }
  place(buffer, size);
}

void Detector::place(void* buffer, std::size_t size) {
  auto* bytes = static_cast<std::uint8_t*>(buffer);
  header_ = new (bytes) Header(bytes + header_bytes(), size - header_bytes(), *index_, limits_);
  impl_ = &header_->impl;
  workspace_size_ = size;
}

void Detector::release() {
  if (header_ != nullptr) header_->~Header();
  if (owned_ != nullptr) ::operator delete (owned_, std::align_val_t{kWorkspaceAlignment});
  header_ = nullptr;
  impl_ = nullptr;
  owned_ = nullptr;
  workspace_size_ = 0;
}

Detector::~Detector() {
  release();
}

Detector::Detector(Detector&& other) noexcept
    : index_(other.index_),
      header_(std::exchange(other.header_, nullptr)),
      impl_(std::exchange(other.impl_, nullptr)),
      owned_(std::exchange(other.owned_, nullptr)),
      workspace_size_(std::exchange(other.workspace_size_, 0)),
      limits_(other.limits_),
      status_(std::move(other.status_)) {
  other.status_ = {StatusCode::kInvalidArgument, "detector was moved from"};
}

Detector& Detector::operator=(Detector&& other) noexcept {
  if (this != &other) {
    release();
    index_ = other.index_;
    header_ = std::exchange(other.header_, nullptr);
    impl_ = std::exchange(other.impl_, nullptr);
    owned_ = std::exchange(other.owned_, nullptr);
    workspace_size_ = std::exchange(other.workspace_size_, 0);
    limits_ = other.limits_;
    status_ = std::move(other.status_);
    other.status_ = {StatusCode::kInvalidArgument, "detector was moved from"};
  }
  return *this;
}

std::size_t Detector::workspace_bytes() const {
  return workspace_size_;
}
std::size_t Detector::workspace_used() const {
  return header_ != nullptr ? header_bytes() + header_->memory.used() : 0;
}
const Status& Detector::status() const {
  return status_;
}
const Limits& Detector::limits() const {
  return limits_;
}
const DetectStats& Detector::stats() const {
  static const DetectStats none{};
  return impl_ != nullptr ? impl_->stats : none;
}
ConstSpan<KeygraphMatch> Detector::last_matches() const {
  if (impl_ == nullptr) return {};
  return {impl_->matches.data(), impl_->matches.size()};
}
ConstSpan<Keypoint> Detector::last_keypoints() const {
  if (impl_ == nullptr) return {};
  return {impl_->scene_keypoints.data(), impl_->scene_keypoints.size()};
}
const ModelIndex& Detector::index() const {
  return *index_;
}

namespace {

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

}  // namespace

Status Detector::detect(ImageView frame, DetectionList& out) {
  out.clear();
  if (impl_ == nullptr) return status_;
  impl_->stats = DetectStats{};
  if (Status s = check_frame(frame, limits_); !s) return s;
  const Params& params = index_->params();
  if (wants_vertex_descriptors(*index_)) return missing_vertex_descriptors();
  if (params.keypoints.detector != KeypointDetector::kHessian)
    return {
        StatusCode::kInvalidArgument,
        "index was built with a keypoint detector the core does not have (MSER): pass keypoints"};
  const int mode = impl_->mode();
  if (mode == 1) return impl_->detect_keypoints_and_run(frame, out);
  if (mode == 3) {
    if (Status s = impl_->detect_keypoints_and_run(frame, out); !s) return s;
  }
  DetectionList& up = mode == 3 ? impl_->upsampled_found : out;
  up.clear();
  const Status s = impl_->detect_keypoints_and_run(impl_->work_frame(frame), up);
  impl_->map_to_frame(up);
  if (mode == 3) impl_->merge(up, out);
  return s;
}

Status Detector::Impl::detect_keypoints_and_run(ImageView frame, DetectionList& out) {
  const auto start = Clock::now();
  if (!hessian.detect(frame, index->params().keypoints, limits.max_keypoints, detected))
    stats.truncated_keypoints = true;
  stats.ms_keypoints += ms_since(start);
  return run(frame, detected.data(), static_cast<int>(detected.size()), nullptr, out, Clock::now());
}

void Detector::Impl::merge(const DetectionList& more, DetectionList& out) {
  for (const Detection& d : more) {
    if (!out.push_back(d)) stats.truncated_detections = true;
  }
  keep_best_of_overlapping(out);
  // Each pass kept up to max_detections; together they may not exceed it.
  // The least supported go first (fewer inliers, then the smaller score
  // over chance, then the later one), in place: no allocation.
  const auto most = static_cast<std::size_t>(limits.max_detections);
  while (out.size() > most) {
    std::size_t worst = 0;
    for (std::size_t i = 1; i < out.size(); ++i) {
      const Detection& a = out[i];
      const Detection& w = out[worst];
      if (a.inliers < w.inliers ||
          (a.inliers == w.inliers && a.score - a.chance <= w.score - w.chance))
        worst = i;
    }
    for (std::size_t i = worst; i + 1 < out.size(); ++i) out[i] = out[i + 1];
    out.truncate(out.size() - 1);
    stats.truncated_detections = true;
  }
}

Status Detector::detect(ImageView frame, const Keypoint* keypoints, int count, DetectionList& out) {
  return detect(frame, keypoints, count, nullptr, out);
}

Status Detector::detect(ImageView frame, const Keypoint* keypoints, int count,
                        const std::uint8_t* vertex_descriptors, DetectionList& out) {
  out.clear();
  if (impl_ == nullptr) return status_;
  impl_->stats = DetectStats{};
  if (Status s = check_frame(frame, limits_); !s) return s;
  if (count < 0 || (count > 0 && keypoints == nullptr))
    return {StatusCode::kInvalidArgument, "bad keypoint array"};
  if (!wants_vertex_descriptors(*index_)) {
    vertex_descriptors = nullptr;
  } else if (vertex_descriptors == nullptr && count > 0) {
    return missing_vertex_descriptors();
  }
  const int mode = impl_->mode();
  if (mode != 2) {
    if (Status s = impl_->run(frame, keypoints, count, vertex_descriptors, out, Clock::now());
        mode == 1 || !s)
      return s;
  }
  const auto start = Clock::now();
  const ImageView work = impl_->work_frame(frame);
  const int given = count;
  impl_->upsample_keypoints(keypoints, count, vertex_descriptors);
  const bool truncated = count < given;
  DetectionList& up = mode == 3 ? impl_->upsampled_found : out;
  up.clear();
  const Status s = impl_->run(work, keypoints, count, vertex_descriptors, up, start);
  impl_->stats.keypoints = given;
  impl_->stats.truncated_keypoints |= truncated;
  impl_->map_to_frame(up);
  if (mode == 3) impl_->merge(up, out);
  return s;
}

ImageView Detector::Impl::work_frame(ImageView frame) {
  if (!upsampling()) return frame;
  upsample2x(frame, upsampled);
  return view_of(upsampled);
}

void Detector::Impl::upsample_keypoints(const Keypoint*& keypoints, int& count,
                                        const std::uint8_t*& descriptors) {
  if (count > limits.max_keypoints) {
    keep_strongest(keypoints, count, descriptors);
    if (descriptors != nullptr) descriptors = detected_descriptors.data();
  } else {
    detected.assign(keypoints, keypoints + count);
  }
  for (Keypoint& k : detected) {
    k.x = to_upsampled(k.x);
    k.y = to_upsampled(k.y);
    k.scale *= 2.f;
  }
  keypoints = detected.data();
  count = static_cast<int>(detected.size());
}

void Detector::Impl::map_to_frame(DetectionList& out) {
  for (Detection& d : out) {
    d.homography = homography_from_upsampled(d.homography);
    for (Point2f& c : d.corners) c = {from_upsampled(c.x), from_upsampled(c.y)};
    d.rms_error *= 0.5;
    // From the mapped support (the inliers stay those of the upsampled
    // frame's keypoints: the model was fitted on frames as they are).
    d.confidence = detection_confidence(d);
  }
  for (Keypoint& k : scene_keypoints) {
    k.x = from_upsampled(k.x);
    k.y = from_upsampled(k.y);
    k.scale *= 0.5f;
  }
}

void Detector::Impl::check_triangle_patches(ImageView frame) {
  const float threshold = index->params().ransac.min_triangle_correlation;
  if (!(threshold > 0.f) || vertex_count(index->params().graph.structure) < 3) return;
  const Point2f* model_points = index->keypoints();
  std::size_t kept = 0;
  for (std::size_t i = 0; i < matches.size(); ++i) {
    KeygraphMatch& m = matches[i];
    const Point2f model[3] = {model_points[m.model_vertices[0]], model_points[m.model_vertices[1]],
                              model_points[m.model_vertices[2]]};
    const Point2f scene[3] = {scene_points[static_cast<std::size_t>(m.scene_vertices[0])],
                              scene_points[static_cast<std::size_t>(m.scene_vertices[1])],
                              scene_points[static_cast<std::size_t>(m.scene_vertices[2])]};
    const TrianglePatch patch =
        triangle_patch_correlation(index->appearance(m.model_id), frame, model, scene);
    if (patch.measured) {
      m.patch_correlation = patch.correlation;
      if (patch.correlation < threshold) continue;
    }
    matches[kept++] = m;
  }
  stats.patch_rejections = static_cast<int>(matches.size() - kept);
  matches.resize(kept);
}

void Detector::Impl::keep_strongest(const Keypoint* keypoints, int count,
                                    const std::uint8_t* descriptors) {
  // A heap of indices (its front the weakest kept), then strongest first.
  const Stronger stronger{keypoints};
  const int keep = limits.max_keypoints;
  order.clear();
  WorkVector<int>& heap = descriptors != nullptr ? order : selected;
  heap.clear();
  for (int i = 0; i < count; ++i)
    offer_strongest(heap, i, static_cast<std::size_t>(std::max(0, keep)), stronger);
  std::sort_heap(heap.begin(), heap.end(), stronger);
  detected.clear();
  for (int i : heap) detected.push_back(keypoints[i]);
  if (descriptors != nullptr) {
    detected_descriptors.resize(heap.size() * kRow);
    for (std::size_t i = 0; i < heap.size(); ++i)
      std::copy_n(descriptors + static_cast<std::size_t>(heap[i]) * kRow, kRow,
                  detected_descriptors.data() + i * kRow);
  }
}

Status Detector::Impl::run(ImageView frame, const Keypoint* keypoints, int count,
                           const std::uint8_t* descriptors, DetectionList& out,
                           Clock::time_point start) {
  const Params& params = index->params();
  stats.keypoints = count;
  if (count > limits.max_keypoints) {
    // Keep the strongest: callers pass keypoints in any order.
    stats.truncated_keypoints = true;
    keep_strongest(keypoints, count, descriptors);
    keypoints = detected.data();
    if (descriptors != nullptr) descriptors = detected_descriptors.data();
    count = limits.max_keypoints;
  }

  // Sampling: a maximal subset with Chebyshev distance >= scene_sample_distance.
  Rng rng(params.ransac.seed);
  sampler.sample(keypoints, count, params.graph.scene_sample_distance,
                 params.graph.scene_sampling == SceneSampling::kRandom ? &rng : nullptr, selected);
  if (static_cast<int>(selected.size()) > limits.max_scene_keypoints) {
    stats.truncated_keypoints = true;
    selected.resize(static_cast<std::size_t>(limits.max_scene_keypoints));
  }
  scene_keypoints.clear();
  scene_points.clear();
  scene_scales.clear();
  for (int i : selected) {
    scene_keypoints.push_back(keypoints[i]);
    scene_points.push_back({keypoints[i].x, keypoints[i].y});
    scene_scales.push_back(keypoints[i].scale);
  }
  stats.sampled_keypoints = static_cast<int>(scene_points.size());
  if (descriptors != nullptr) {
    scene_descriptors.resize(selected.size() * kRow);
    scene_inverse_norms.resize(selected.size());
    for (std::size_t i = 0; i < selected.size(); ++i) {
      std::uint8_t* row = scene_descriptors.data() + i * kRow;
      std::copy_n(descriptors + static_cast<std::size_t>(selected[i]) * kRow, kRow, row);
      scene_inverse_norms[i] = vertex_inverse_norm(row);
    }
  }

  // Scene keygraphs from the Delaunay triangulation.
  triangulation.triangulate(scene_points.data(), static_cast<int>(scene_points.size()));
  scene_keygraphs(triangulation, scene_points.data(), params.graph.structure, keygraphs);
  stats.keygraphs = static_cast<int>(keygraphs.size());
  stats.ms_graph = ms_since(start);

  // Descriptors are computed lazily inside selection; the blur is shared.
  auto t = Clock::now();
  gaussian_blur(frame, params.descriptor.blur_sigma, blurred, blur_scratch);
  stats.ms_describe = ms_since(t);

  t = Clock::now();
  SelectionInput in;
  in.index = index;
  in.search = &search;
  in.blurred = view_of(blurred);
  in.scene_points = scene_points.data();
  in.scene_scales = scene_scales.data();
  in.triangulation = &triangulation;
  in.keygraphs = &keygraphs;
  if (descriptors != nullptr) {
    in.model_descriptors = index->vertex_descriptors();
    in.model_inverse_norms = model_inverse_norms.data();
    in.scene_descriptors = scene_descriptors.data();
    in.scene_inverse_norms = scene_inverse_norms.data();
  }
  if (completes_circuits(params)) in.adjacency = &adjacency;
  selector.select(in, limits, matches, stats);
  check_triangle_patches(view_of(blurred));
  stats.ms_select = ms_since(t);

  // Pose per model, over that model's correspondences.
  t = Clock::now();
  FrameKeypoints frame_keypoints;
  frame_keypoints.keypoints = keypoints;
  frame_keypoints.count = count;
  frame_keypoints.width = frame.width;
  frame_keypoints.height = frame.height;
  frame_keypoints.image = view_of(blurred);
  if (!matches.empty()) {
    grid.build(keypoints, count, frame.width, frame.height,
               std::max(4.f, static_cast<float>(params.ransac.inlier_threshold)));
  }
  frame_keypoints.grid = &grid;
  // Group the correspondences by model, keeping their order (a counting
  // sort: no temporary buffer beyond the reserved ones).
  const auto models = static_cast<std::size_t>(index->model_count());
  model_begin.assign(models + 1, 0);
  for (const KeygraphMatch& m : matches) ++model_begin[static_cast<std::size_t>(m.model_id) + 1];
  for (std::size_t i = 0; i < models; ++i) model_begin[i + 1] += model_begin[i];
  grouped.resize(matches.size());
  for (const KeygraphMatch& m : matches)
    grouped[model_begin[static_cast<std::size_t>(m.model_id)]++] = m;
  std::size_t begin = 0;
  while (begin < grouped.size()) {
    std::size_t end = begin;
    while (end < grouped.size() && grouped[end].model_id == grouped[begin].model_id) ++end;
    Rng model_rng(params.ransac.seed ^ (0x9e3779b97f4a7c15ULL *
                                        static_cast<std::uint64_t>(grouped[begin].model_id + 1)));
    stats.ransac_iterations +=
        pose.estimate(*index, grouped[begin].model_id, grouped.data() + begin,
                      static_cast<int>(end - begin), scene_points.data(), frame_keypoints,
                      model_rng, limits.max_detections, out, stats.truncated_detections);
    begin = end;
  }
  keep_best_of_overlapping(out);
  stats.ms_pose = ms_since(t);
  if (stats.truncated_keypoints || stats.truncated_arc_matches || stats.truncated_correspondences ||
      stats.truncated_detections)
    KG_LOG("limits reached: keypoints %d, arc matches %d, correspondences %d, detections %d",
           stats.truncated_keypoints, stats.truncated_arc_matches, stats.truncated_correspondences,
           stats.truncated_detections);
  return Status::ok();
}

}  // namespace kg
