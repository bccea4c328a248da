#include "keygraph/detector.h"

#include <algorithm>
#include <chrono>

#include "core/blur.h"
#include "core/delaunay.h"
#include "core/hessian.h"
#include "core/kdtree.h"
#include "core/keygraph.h"
#include "core/plane.h"
#include "core/pose.h"
#include "core/rng.h"
#include "core/sampling.h"
#include "core/selection.h"
#include "core/vertex_descriptor.h"

namespace kg {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

constexpr auto kRow = static_cast<std::size_t>(kVertexDescriptorSize);

bool wants_vertex_descriptors(const ModelIndex& index) {
  return index.params().descriptor.vertex_descriptor != VertexDescriptor::kNone;
}

Status missing_vertex_descriptors() {
  return {StatusCode::kInvalidArgument,
          "index was built with SIFT vertex descriptors, which the core cannot compute: pass "
          "keypoints with their descriptors (DesktopDetector does)"};
}

}  // namespace

struct Detector::Impl {
  const ModelIndex* index = nullptr;
  Limits limits;
  ArcSearch search;
  DetectStats stats;

  HessianDetector hessian;
  std::vector<Keypoint> detected;
  // Vertex descriptors: of the model keypoints' inverse norms (once), of the
  // strongest keypoints when the input is cut to max_keypoints, and of the
  // sampled keypoints.
  std::vector<float> model_inverse_norms;
  std::vector<int> order;
  std::vector<std::uint8_t> detected_descriptors;
  std::vector<std::uint8_t> scene_descriptors;
  std::vector<float> scene_inverse_norms;
  Plane<std::uint8_t> blurred;
  Plane<float> blur_scratch;
  SeparatedSampler sampler;
  std::vector<int> selected;
  std::vector<Keypoint> scene_keypoints;
  std::vector<Point2f> scene_points;
  std::vector<float> scene_scales;
  Delaunay triangulation;
  std::vector<SceneKeygraph> keygraphs;
  Selector selector;
  std::vector<KeygraphMatch> matches;
  std::vector<KeygraphMatch> model_matches;
  PoseEstimator pose;
  PointGrid grid;

  Status run(ImageView frame, const Keypoint* keypoints, int count, const std::uint8_t* descriptors,
             DetectionList& out, Clock::time_point start);
};

Detector::Detector(const ModelIndex& index, const Limits& limits) : impl_(new Impl) {
  impl_->index = &index;
  impl_->limits = limits;
  impl_->search = ArcSearch(index);
  impl_->detected.reserve(static_cast<std::size_t>(std::max(0, limits.max_keypoints)));
  impl_->matches.reserve(static_cast<std::size_t>(std::max(0, limits.max_correspondences)));
  if (const std::uint8_t* v = index.vertex_descriptors()) {
    impl_->model_inverse_norms.resize(index.keypoint_count());
    for (std::uint32_t i = 0; i < index.keypoint_count(); ++i)
      impl_->model_inverse_norms[i] = vertex_inverse_norm(v + i * kRow);
    const auto frame_keypoints = static_cast<std::size_t>(std::max(0, limits.max_keypoints));
    impl_->order.reserve(frame_keypoints);
    impl_->detected_descriptors.reserve(frame_keypoints * kRow);
    impl_->scene_descriptors.reserve(
        static_cast<std::size_t>(std::max(0, limits.max_scene_keypoints)) * kRow);
    impl_->scene_inverse_norms.reserve(
        static_cast<std::size_t>(std::max(0, limits.max_scene_keypoints)));
  }
}

Detector::~Detector() = default;
Detector::Detector(Detector&&) noexcept = default;
Detector& Detector::operator=(Detector&&) noexcept = default;

const DetectStats& Detector::stats() const {
  return impl_->stats;
}
const std::vector<KeygraphMatch>& Detector::last_matches() const {
  return impl_->matches;
}
const std::vector<Keypoint>& Detector::last_keypoints() const {
  return impl_->scene_keypoints;
}
const ModelIndex& Detector::index() const {
  return *impl_->index;
}

Status Detector::detect(ImageView frame, DetectionList& out) {
  out.clear();
  impl_->stats = DetectStats{};
  if (frame.empty() || frame.stride < frame.width)
    return {StatusCode::kInvalidArgument, "empty or malformed frame"};
  const Params& params = impl_->index->params();
  if (wants_vertex_descriptors(*impl_->index)) return missing_vertex_descriptors();
  if (params.keypoints.detector != KeypointDetector::kHessian)
    return {
        StatusCode::kInvalidArgument,
        "index was built with a keypoint detector the core does not have (MSER): pass keypoints"};
  const auto start = Clock::now();
  impl_->hessian.detect(frame, params.keypoints, impl_->limits.max_keypoints, impl_->detected);
  impl_->stats.ms_keypoints = ms_since(start);
  return impl_->run(frame, impl_->detected.data(), static_cast<int>(impl_->detected.size()),
                    nullptr, out, Clock::now());
}

Status Detector::detect(ImageView frame, const Keypoint* keypoints, int count, DetectionList& out) {
  return detect(frame, keypoints, count, nullptr, out);
}

Status Detector::detect(ImageView frame, const Keypoint* keypoints, int count,
                        const std::uint8_t* vertex_descriptors, DetectionList& out) {
  out.clear();
  impl_->stats = DetectStats{};
  if (frame.empty() || frame.stride < frame.width)
    return {StatusCode::kInvalidArgument, "empty or malformed frame"};
  if (count < 0 || (count > 0 && keypoints == nullptr))
    return {StatusCode::kInvalidArgument, "bad keypoint array"};
  if (!wants_vertex_descriptors(*impl_->index)) {
    vertex_descriptors = nullptr;
  } else if (vertex_descriptors == nullptr && count > 0) {
    return missing_vertex_descriptors();
  }
  return impl_->run(frame, keypoints, count, vertex_descriptors, out, Clock::now());
}

Status Detector::Impl::run(ImageView frame, const Keypoint* keypoints, int count,
                           const std::uint8_t* descriptors, DetectionList& out,
                           Clock::time_point start) {
  const Params& params = index->params();
  stats.keypoints = count;
  if (count > limits.max_keypoints && descriptors != nullptr) {
    // As below, carrying each keypoint's descriptor along (ties by input order).
    stats.truncated_keypoints = true;
    order.resize(static_cast<std::size_t>(count));
    for (int i = 0; i < count; ++i) order[static_cast<std::size_t>(i)] = i;
    std::partial_sort(order.begin(), order.begin() + limits.max_keypoints, order.end(),
                      [keypoints](int a, int b) {
                        return keypoints[a].response > keypoints[b].response ||
                               (keypoints[a].response == keypoints[b].response && a < b);
                      });
    order.resize(static_cast<std::size_t>(limits.max_keypoints));
    detected.clear();
    detected_descriptors.resize(order.size() * kRow);
    for (std::size_t i = 0; i < order.size(); ++i) {
      detected.push_back(keypoints[order[i]]);
      std::copy_n(descriptors + static_cast<std::size_t>(order[i]) * kRow, kRow,
                  detected_descriptors.data() + i * kRow);
    }
    keypoints = detected.data();
    descriptors = detected_descriptors.data();
    count = limits.max_keypoints;
  } else if (count > limits.max_keypoints) {
    // Keep the strongest: callers pass keypoints in any order.
    stats.truncated_keypoints = true;
    detected.assign(keypoints, keypoints + count);
    std::partial_sort(detected.begin(), detected.begin() + limits.max_keypoints, detected.end(),
                      [](const Keypoint& a, const Keypoint& b) { return a.response > b.response; });
    detected.resize(static_cast<std::size_t>(limits.max_keypoints));
    keypoints = detected.data();
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
  selector.select(in, limits, matches, stats);
  stats.ms_select = ms_since(t);

  // Pose per model, over that model's correspondences.
  t = Clock::now();
  FrameKeypoints frame_keypoints;
  frame_keypoints.keypoints = keypoints;
  frame_keypoints.count = count;
  frame_keypoints.width = frame.width;
  frame_keypoints.height = frame.height;
  if (!matches.empty()) {
    grid.build(keypoints, count, frame.width, frame.height,
               std::max(4.f, static_cast<float>(params.ransac.inlier_threshold)));
  }
  frame_keypoints.grid = &grid;
  std::stable_sort(
      matches.begin(), matches.end(),
      [](const KeygraphMatch& a, const KeygraphMatch& b) { return a.model_id < b.model_id; });
  std::size_t begin = 0;
  while (begin < matches.size()) {
    std::size_t end = begin;
    while (end < matches.size() && matches[end].model_id == matches[begin].model_id) ++end;
    Rng model_rng(params.ransac.seed ^ (0x9e3779b97f4a7c15ULL *
                                        static_cast<std::uint64_t>(matches[begin].model_id + 1)));
    stats.ransac_iterations +=
        pose.estimate(*index, matches[begin].model_id, matches.data() + begin,
                      static_cast<int>(end - begin), scene_points.data(), frame_keypoints,
                      model_rng, limits.max_detections, out, stats.truncated_detections);
    begin = end;
  }
  stats.ms_pose = ms_since(t);
  return Status::ok();
}

}  // namespace kg
