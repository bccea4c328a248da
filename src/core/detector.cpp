// The Detector's contract (keygraph/detector.h): its one workspace, its
// options, and the frame's entry points, which hand over to the pipeline
// (core/pipeline/frame_pipeline.h).
#include "keygraph/detector.h"

#include <cstdlib>
#include <new>
#include <string>
#include <utility>

#include "core/pipeline/frame_pipeline.h"
#include "core/support/page_memory.h"
#include "core/support/workspace.h"
#include "keygraph/param_text.h"

namespace kg {

namespace {

Status check_limits(const Limits& l) {
  const bool ok = l.max_width >= 1 && l.max_height >= 1 && l.max_width <= Limits::kMaxSide &&
                  l.max_height <= Limits::kMaxSide && l.max_keypoints >= 1 &&
                  l.max_scene_keypoints >= 1 && l.max_arc_matches >= 1 && l.max_arc_pool >= 1 &&
                  l.max_correspondences >= 1 && l.max_detections >= 1 &&
                  l.max_detections <= kMaxDetections && l.threads >= 1 && l.threads <= 64;
  if (ok) return Status::ok();
  return {StatusCode::kInvalidArgument,
          "detector limits out of range (frame 1..16384 px a side, every count >= 1, "
          "max_detections <= " +
              std::to_string(kMaxDetections) + ", threads <= 64)"};
}

// check_limits(), and the upsampled frame within the largest side too (a
// larger one would ask for a workspace of gigabytes).
Status check_limits(const Limits& l, const Params& params) {
  if (Status s = check_limits(l); !s) return s;
  // 4 upsamples only a window of the frame.
  const int mode = params.keypoints.scene_upsample;
  const int f = mode == 2 || mode == 3 ? 2 : 1;
  if (f * l.max_width <= Limits::kMaxSide && f * l.max_height <= Limits::kMaxSide)
    return Status::ok();
  return {StatusCode::kInvalidArgument,
          "detector limits out of range: with keypoints.scene_upsample 2 or 3 the frame is "
          "upsampled 2x, so at most " +
              std::to_string(Limits::kMaxSide / 2) + " px a side"};
}

// The runtime options among the index's parameters (keygraph/param_text.h
// names): every RANSAC setting and the search effort.
bool is_detect_option(std::string_view name) {
  return name.substr(0, 7) == "ransac." || name == "descriptor.max_search_leaves" ||
         name == "descriptor.search_reference_models";
}

}  // namespace

DetectOptions DetectOptions::from(const ModelIndex& index) {
  const Params& p = index.params();
  DetectOptions o;
  o.ransac = p.ransac;
  o.max_search_leaves = p.descriptor.max_search_leaves;
  o.search_reference_models = p.descriptor.search_reference_models;
  return o;
}

Status set_detect_option(DetectOptions& options, std::string_view name, std::string_view value) {
  if (name == "search_arcs_per_leaf" || name == "ransac_barren_draws" ||
      name == "upsampled_scene_keypoints") {
    const std::string text(value);
    char* end = nullptr;
    const long v = std::strtol(text.c_str(), &end, 10);
    if (text.empty() || end != text.c_str() + text.size() || v < 0 || v > 1 << 20)
      return {StatusCode::kInvalidArgument, "bad value '" + text + "' for " + std::string(name)};
    int& field = name == "search_arcs_per_leaf"  ? options.search_arcs_per_leaf
                 : name == "ransac_barren_draws" ? options.ransac_barren_draws
                                                 : options.upsampled_scene_keypoints;
    field = static_cast<int>(v);
    return Status::ok();
  }
  if (name == "align_coarse_min_ncc" || name == "align_min_ncc") {
    const std::string text(value);
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || !(v >= -1.0 && v <= 1.0))
      return {StatusCode::kInvalidArgument, "bad value '" + text + "' for " + std::string(name) +
                                                " (a correlation in [-1, 1]; -1: never)"};
    (name == "align_min_ncc" ? options.align_min_ncc : options.align_coarse_min_ncc) = v;
    return Status::ok();
  }
  if (name == "min_confidence" || name == "time_budget_ms" || name == "upsampled_min_confidence") {
    const std::string text(value);
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size())
      return {StatusCode::kInvalidArgument, "bad value '" + text + "' for " + std::string(name)};
    double& field = name == "min_confidence"   ? options.min_confidence
                    : name == "time_budget_ms" ? options.time_budget_ms
                                               : options.upsampled_min_confidence;
    field = v;
    return Status::ok();
  }
  if (!is_detect_option(name)) {
    std::string unused;
    if (param_value_text(Params{}, name, unused))
      return {StatusCode::kInvalidArgument,
              std::string(name) +
                  " is fixed by the index (the models were built with it): rebuild the index "
                  "with keygraph build --set to change it"};
    return {StatusCode::kInvalidArgument, "unknown option '" + std::string(name) + "'"};
  }
  Params p;
  p.ransac = options.ransac;
  p.descriptor.max_search_leaves = options.max_search_leaves;
  p.descriptor.search_reference_models = options.search_reference_models;
  if (Status s = set_param(p, name, value); !s) return s;
  options.ransac = p.ransac;
  options.max_search_leaves = p.descriptor.max_search_leaves;
  options.search_reference_models = p.descriptor.search_reference_models;
  return Status::ok();
}

std::vector<std::string> detect_option_names() {
  std::vector<std::string> names;
  for (std::string& n : param_names())
    if (is_detect_option(n)) names.push_back(std::move(n));
  names.emplace_back("search_arcs_per_leaf");
  names.emplace_back("ransac_barren_draws");
  names.emplace_back("align_coarse_min_ncc");
  names.emplace_back("align_min_ncc");
  names.emplace_back("min_confidence");
  names.emplace_back("time_budget_ms");
  names.emplace_back("upsampled_min_confidence");
  names.emplace_back("upsampled_scene_keypoints");
  return names;
}

// What a workspace block starts with: the bump allocator over the rest of
// the block, and the pipeline, whose buffers come from it.
struct Detector::Header {
  Header(std::uint8_t* rest, std::size_t rest_size, const ModelIndex& index, const Limits& limits,
         const DetectOptions& options)
      : memory(rest, rest_size), pipeline(index, limits, options, &memory, true) {}
  Workspace memory;
  FramePipeline pipeline;
};

std::size_t Detector::header_bytes() {
  return align_up(sizeof(Header), kWorkspaceAlignment);
}

std::size_t Detector::workspace_bytes(const ModelIndex& index, const Limits& limits) {
  if (!check_limits(limits, index.params())) return 0;
  // The constructor's own reserve() calls, counted: nothing is allocated.
  MeasuringResource measure;
  const FramePipeline dry(index, limits, DetectOptions::from(index), &measure, false);
  return header_bytes() + measure.measured();
}

Detector::Detector(const ModelIndex& index, const Limits& limits)
    : Detector(index, limits, DetectOptions::from(index)) {}

Detector::Detector(const ModelIndex& index, const Limits& limits, const DetectOptions& options)
    : index_(&index), limits_(limits) {
  status_ = check_limits(limits, index.params());
  if (status_) status_ = FramePipeline::check_options(index, options);
  if (!status_) return;
  const std::size_t bytes = workspace_bytes(index, limits);
  owned_ = allocate_pages(bytes);
  if (owned_ == nullptr) {
    status_ = {StatusCode::kResourceExhausted,
               "cannot allocate the detector's workspace of " + std::to_string(bytes) + " bytes"};
    return;
  }
  place(owned_, bytes, options);
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
  place(buffer, size, DetectOptions::from(index));
}

void Detector::place(void* buffer, std::size_t size, const DetectOptions& options) {
  auto* bytes = static_cast<std::uint8_t*>(buffer);
  header_ =
      new (bytes) Header(bytes + header_bytes(), size - header_bytes(), *index_, limits_, options);
  pipeline_ = &header_->pipeline;
  workspace_size_ = size;
}

void Detector::release() {
  if (header_ != nullptr) header_->~Header();
  if (owned_ != nullptr) release_pages(owned_, workspace_size_);
  header_ = nullptr;
  pipeline_ = nullptr;
  owned_ = nullptr;
  workspace_size_ = 0;
}

Detector::~Detector() {
  release();
}

Detector::Detector(Detector&& other) noexcept
    : index_(other.index_),
      header_(std::exchange(other.header_, nullptr)),
      pipeline_(std::exchange(other.pipeline_, nullptr)),
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
    pipeline_ = std::exchange(other.pipeline_, nullptr);
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

Status Detector::set_options(const DetectOptions& options) {
  if (pipeline_ == nullptr) return status_;
  if (Status s = FramePipeline::check_options(*index_, options); !s) return s;
  pipeline_->set_options(options);
  return Status::ok();
}

Status Detector::check_options(const ModelIndex& index, const DetectOptions& options) {
  return FramePipeline::check_options(index, options);
}

const DetectOptions& Detector::options() const {
  static const DetectOptions none{};
  return pipeline_ != nullptr ? pipeline_->options() : none;
}

bool Detector::searches_model(int id) const {
  return pipeline_ != nullptr && pipeline_->searches_model(id);
}

const DetectStats& Detector::stats() const {
  static const DetectStats none{};
  return pipeline_ != nullptr ? pipeline_->stats() : none;
}
ConstSpan<KeygraphMatch> Detector::last_matches() const {
  if (pipeline_ == nullptr) return {};
  return {pipeline_->matches().data(), pipeline_->matches().size()};
}
ConstSpan<Keypoint> Detector::last_keypoints() const {
  if (pipeline_ == nullptr) return {};
  return {pipeline_->scene_keypoints().data(), pipeline_->scene_keypoints().size()};
}
const ModelIndex& Detector::index() const {
  return *index_;
}

Status Detector::detect(ImageView frame, DetectionList& out) {
  out.clear();
  if (pipeline_ == nullptr) return status_;
  return pipeline_->detect(frame, out);
}

Status Detector::detect(ImageView frame, const Keypoint* keypoints, int count, DetectionList& out) {
  return detect(frame, keypoints, count, nullptr, out);
}

Status Detector::detect(ImageView frame, const Keypoint* keypoints, int count,
                        const std::uint8_t* vertex_descriptors, DetectionList& out) {
  out.clear();
  if (pipeline_ == nullptr) return status_;
  return pipeline_->detect(frame, keypoints, count, vertex_descriptors, out);
}

}  // namespace kg
