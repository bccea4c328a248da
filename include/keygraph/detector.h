// Per-frame detection of the models of a ModelIndex (paper sections 5-7).
//
//   kg::ModelIndex index;
//   if (auto s = kg::ModelIndex::open("signs.kgi", index); !s) { ... }
//   kg::Detector detector(index);            // one workspace, allocated here
//   kg::DetectionList found;                 // fixed capacity, no heap
//   detector.detect(kg::ImageView{data, w, h, stride}, found);
//
// Memory: the constructor lays out one workspace for `Limits` (frame size,
// keypoints, keygraphs, correspondences, detections) and allocates it in one
// piece, or uses a buffer the caller supplies; detect() never allocates. When
// a frame needs more than the limits allow, detection degrades (the stats'
// truncated_* flags say what was cut) instead of overflowing. A frame larger
// than max_width x max_height is an error.
//
// The index must outlive the detector. A Detector is not thread-safe; use
// one per thread (they can share one index).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "keygraph/image.h"
#include "keygraph/model_index.h"
#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg {

inline constexpr int kMaxDetections = 64;  // capacity of a DetectionList

// Capacities of the per-frame work, from which the workspace is sized.
// Reaching one degrades detection (the stats say what was cut); it never
// overflows. Detector::workspace_bytes() gives the memory they need (about
// 30 MB for the defaults at 640x480, 16 MB of it the arc pool:
// tests/core/test_runtime_memory.cpp).
struct Limits {
  static constexpr int kMaxSide = 16384;  // the largest max_width, max_height
  int max_width = 640;                    // largest frame, pixels
  int max_height = 480;
  int max_keypoints = 4000;        // detector output, strongest kept
  int max_scene_keypoints = 2000;  // after Chebyshev sampling
  int max_arc_matches = 4096;      // model arcs kept per scene arc query
  // Model arcs kept over all queries of a frame (8 bytes each): 2 M holds
  // a 640x480 frame's look-ups in a 50-sign index, whose search budget
  // grows with it (DescriptorParams::search_reference_models); 512 K cut
  // them off. Indexes of hundreds of models may fill it again, and a grown
  // budget may find more than max_arc_matches arcs for one query: both
  // degrade as any limit does (DetectStats::truncated_arc_matches).
  int max_arc_pool = 1 << 21;
  int max_correspondences = 20000;  // keygraph correspondences per frame
  int max_detections = 16;          // at most kMaxDetections
  // The same limits for frames up to width x height.
  Limits for_frame(int width, int height) const {
    Limits l = *this;
    l.max_width = width;
    l.max_height = height;
    return l;
  }
};

struct Detection {
  int model_id = -1;
  std::string_view model_name;  // points into the index
  Homography homography{};      // model pixels -> scene pixels
  Point2f corners[4];           // model outline mapped into the scene
  int inliers = 0;              // distinct keypoint correspondences within threshold
  int inlier_keygraphs = 0;     // keygraph correspondences all of whose vertices are inliers
  // Fraction of the model's keypoints that project inside the frame and
  // find a frame keypoint within the inlier threshold under the final pose
  // (chance level is the frame's keypoint density times the threshold disk).
  double score = 0.0;
  double chance = 0.0;     // the same fraction for the pose shifted by 3 thresholds
  double rms_error = 0.0;  // refined reprojection error of the inliers, pixels
  // Binomial z-score of `score` against `chance` (over the model keypoints
  // the views say the pose's scale should show): the verification's test.
  double verification_z = 0.0;
  // Normalised cross-correlation of the model's appearance image (stored in
  // the index, format 6.2) with the frame under the final pose, after the
  // photometric refinement aligned it: in [0, 1] (a negative correlation is
  // reported as 0); -1 when not measured (an index without appearances,
  // most of the model outside the frame, a flat or tiny appearance, or a
  // degenerate pose).
  double appearance = -1.0;
  // Estimated probability, in [0, 1], that the detection is right (the right
  // model, every corner within 10 px): a logistic model of the support
  // above, fitted on the sign benchmark (core/pose/confidence.h). Threshold it to
  // trade detections for fewer false ones (docs/RESULTS.md, "Confidence").
  double confidence = 0.0;
  int ransac_iterations = 0;
};

struct DetectStats {
  int keypoints = 0;          // detected in the frame
  int sampled_keypoints = 0;  // after Chebyshev sampling
  int keygraphs = 0;          // scene keygraphs (Delaunay)
  int arcs_described = 0;     // scene arcs with a valid descriptor
  // Model arcs found similar to them (descriptor and scale attributes), summed.
  long long arc_matches = 0;
  int correspondences = 0;  // keygraph correspondences selected
  // Keygraph correspondences whose arcs all matched but a vertex pair did
  // not (vertex descriptors only).
  long long vertex_rejections = 0;
  // Keygraph correspondences dropped by the triangle patch check
  // (RansacParams::min_triangle_correlation); correspondences counts them.
  int patch_rejections = 0;
  int ransac_iterations = 0;  // summed over models and instances
  // Circuit completion (GraphParams::complete_circuits), summed over the
  // keygraphs: model triples joined from two arcs similar to scene arcs,
  // of which clockwise, of which a plausible local map (whose closing arc
  // is then looked up in the model), and of which the closing arc is
  // similar to the third scene arc too (counted before the output's
  // capacity is checked). A circuit that several passes find is counted
  // once per pass. With scene_upsample 3, of the last pass only (as
  // correspondences).
  long long completion_tried = 0;
  long long completion_clockwise = 0;
  long long completion_plausible = 0;
  long long completion_closed = 0;
  bool truncated_keypoints = false;
  bool truncated_arc_matches = false;
  bool truncated_correspondences = false;
  bool truncated_detections = false;
  // Time per stage, milliseconds (steady clock).
  double ms_keypoints = 0, ms_graph = 0, ms_describe = 0, ms_select = 0, ms_pose = 0;
};

// Detections of one frame: a fixed-capacity list (no heap), filled by
// Detector::detect().
class DetectionList {
 public:
  using value_type = Detection;
  using iterator = Detection*;
  using const_iterator = const Detection*;

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  static constexpr std::size_t capacity() { return kMaxDetections; }
  void clear() { size_ = 0; }
  // Keeps the first `size` detections (no effect when there are fewer).
  void truncate(std::size_t size) { size_ = size < size_ ? size : size_; }
  // False (and nothing added) when full.
  bool push_back(const Detection& d) {
    if (size_ == capacity()) return false;
    items_[size_++] = d;
    return true;
  }
  Detection& operator[](std::size_t i) { return items_[i]; }
  const Detection& operator[](std::size_t i) const { return items_[i]; }
  iterator begin() { return items_; }
  iterator end() { return items_ + size_; }
  const_iterator begin() const { return items_; }
  const_iterator end() const { return items_ + size_; }

 private:
  Detection items_[kMaxDetections];
  std::size_t size_ = 0;
};

// A read-only view of an array the detector owns (valid until the next
// detect() call or the detector's end).
template <class T>
class ConstSpan {
 public:
  ConstSpan() = default;
  ConstSpan(const T* data, std::size_t size) : data_(data), size_(size) {}
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const T* data() const { return data_; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }

 private:
  const T* data_ = nullptr;
  std::size_t size_ = 0;
};

// One keygraph correspondence: model keypoint ids (global) and scene
// keypoint positions for each vertex of the structure.
struct KeygraphMatch {
  int model_id = -1;
  std::uint32_t model_vertices[4] = {0, 0, 0, 0};
  std::int32_t scene_vertices[4] = {0, 0, 0, 0};  // indices into the frame's keypoints
  // The triangle patch correlation of the first three vertices
  // (RansacParams::min_triangle_correlation), in [-1, 1]; 0, neutral, when
  // the check is off or could not judge the correspondence.
  float patch_correlation = 0.f;
};

class Detector {
 public:
  // Allocates the workspace for `limits` (one allocation).
  explicit Detector(const ModelIndex& index, const Limits& limits = Limits{});
  // Uses `size` bytes at `buffer` (64-byte aligned, at least
  // workspace_bytes(index, limits)) as the workspace and allocates nothing;
  // the caller keeps the buffer alive and untouched while the detector
  // exists. A buffer too small or misaligned leaves the detector failed:
  // status() says why and detect() returns that status.
  Detector(const ModelIndex& index, const Limits& limits, void* buffer, std::size_t size);
  ~Detector();
  Detector(Detector&&) noexcept;
  Detector& operator=(Detector&&) noexcept;
  Detector(const Detector&) = delete;
  Detector& operator=(const Detector&) = delete;

  // Bytes of workspace a Detector for `index` and `limits` uses. Found by
  // laying the workspace out once, which allocates temporarily: call it
  // where a heap exists (the figure is the same on every run of one build).
  static std::size_t workspace_bytes(const ModelIndex& index, const Limits& limits);
  std::size_t workspace_bytes() const;
  // Bytes of the workspace handed out so far: equal to workspace_bytes()
  // after construction and, since detect() allocates nothing, ever after.
  std::size_t workspace_used() const;
  // Ok, or why construction failed (limits out of range, buffer too small).
  const Status& status() const;
  const Limits& limits() const;

  // Detects with the built-in keypoint detector (the index's detector must
  // be kHessian, and the index must have no vertex descriptors). Clears and
  // fills `out`.
  Status detect(ImageView frame, DetectionList& out);
  // Detects with keypoints computed by the caller (e.g. MSER on a desktop):
  // the same pipeline from the sampling step on. The index must have no
  // vertex descriptors.
  Status detect(ImageView frame, const Keypoint* keypoints, int count, DetectionList& out);
  // The same with the keypoints' vertex descriptors (the core cannot compute
  // SIFT): kVertexDescriptorSize bytes per keypoint, row i describing
  // keypoints[i], computed as the index's were (DesktopDetector does).
  // Required when the index has vertex descriptors (params().descriptor.
  // vertex_descriptor != kNone), ignored otherwise; nullptr means none.
  Status detect(ImageView frame, const Keypoint* keypoints, int count,
                const std::uint8_t* vertex_descriptors, DetectionList& out);

  const DetectStats& stats() const;
  // Keygraph correspondences selected in the last frame (evaluation, tests).
  ConstSpan<KeygraphMatch> last_matches() const;
  // Scene keypoints (after sampling) of the last frame.
  ConstSpan<Keypoint> last_keypoints() const;
  const ModelIndex& index() const;

 private:
  struct Impl;
  struct Header;  // at the start of the workspace: its allocator and the Impl
  static std::size_t header_bytes();
  void place(void* buffer, std::size_t size);
  void release();

  const ModelIndex* index_ = nullptr;
  Header* header_ = nullptr;  // at the start of the workspace
  Impl* impl_ = nullptr;      // header_->impl
  void* owned_ = nullptr;     // the workspace, when the detector allocated it
  std::size_t workspace_size_ = 0;
  Limits limits_;
  Status status_;
};

}  // namespace kg
