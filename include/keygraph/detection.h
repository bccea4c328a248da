// What a detection returns: the objects found in a frame (Detection, in a
// fixed-capacity DetectionList), the frame's statistics (DetectStats) and,
// for evaluation, the keygraph correspondences it selected (KeygraphMatch).
//
// Conventions: pixel (x, y) is column x, row y, the centre of the top-left
// pixel is (0, 0) (keygraph/image.h); a homography maps model pixels (of
// the model image the index was built from, or its ROI) to frame pixels,
// x_frame ~ H x_model (keygraph/types.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "keygraph/types.h"

namespace kg {

inline constexpr int kMaxDetections = 64;  // capacity of a DetectionList

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
  // trade detections for fewer false ones (docs/RESULTS.md, "Detection confidence").
  double confidence = 0.0;
  int ransac_iterations = 0;
  // Tracker (keygraph/tracker.h) only: the object's id while it is
  // followed (-1: not tracked), and whether this frame confirmed it around
  // its predicted pose (true) or detection found it (false). A Detector
  // alone reports -1 and false.
  int track_id = -1;
  bool tracked = false;
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
  // Clusters whose model appearance was aligned onto the frame, and of
  // those the alignments stopped after the coarse level
  // (DetectOptions::align_coarse_min_ncc).
  int alignments = 0;
  int alignments_abandoned = 0;
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
  // The keytuple join's first cut (a semi-join on the keypoints that can
  // close a circuit): model arcs it received from the searches, and kept.
  long long join_arcs_in = 0;
  long long join_arcs_kept = 0;
  bool truncated_keypoints = false;
  bool truncated_arc_matches = false;
  bool truncated_correspondences = false;
  bool truncated_detections = false;
  // Time per stage, milliseconds (steady clock).
  double ms_keypoints = 0, ms_graph = 0, ms_describe = 0, ms_select = 0, ms_pose = 0;
  // DetectOptions::time_budget_ms ran out: the stage it ran out in
  // ("keypoints", "keygraphs", "description", "selection", "pose"), whose
  // work and every later stage's was cut short; nullptr when it did not.
  const char* stopped_early = nullptr;
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

}  // namespace kg
