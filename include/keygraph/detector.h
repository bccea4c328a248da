// Per-frame detection of the models of a ModelIndex (paper sections 5-7).
//
//   kg::ModelIndex index;
//   if (auto s = kg::ModelIndex::open("signs.kgi", index); !s) { ... }
//   kg::Detector detector(index);            // sizes its buffers once
//   kg::DetectionList found;
//   detector.detect(kg::ImageView{data, w, h, stride}, found);
//
// The index must outlive the detector. A Detector is not thread-safe; use
// one per thread (they can share one index).
#pragma once

#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "keygraph/image.h"
#include "keygraph/model_index.h"
#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg {

// Capacities of the per-frame work. Reaching one degrades detection (the
// stats say what was cut); it never overflows.
struct Limits {
  int max_keypoints = 4000;          // detector output, strongest kept
  int max_scene_keypoints = 2000;    // after Chebyshev sampling
  int max_arc_matches = 4096;        // model arcs kept per scene arc query
  int max_correspondences = 200000;  // keygraph correspondences per frame
  int max_detections = 16;
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
  int ransac_iterations = 0;  // summed over models and instances
  bool truncated_keypoints = false;
  bool truncated_arc_matches = false;
  bool truncated_correspondences = false;
  bool truncated_detections = false;
  // Time per stage, milliseconds (steady clock).
  double ms_keypoints = 0, ms_graph = 0, ms_describe = 0, ms_select = 0, ms_pose = 0;
};

using DetectionList = std::vector<Detection>;

// One keygraph correspondence: model keypoint ids (global) and scene
// keypoint positions for each vertex of the structure.
struct KeygraphMatch {
  int model_id = -1;
  std::uint32_t model_vertices[4] = {0, 0, 0, 0};
  std::int32_t scene_vertices[4] = {0, 0, 0, 0};  // indices into the frame's keypoints
};

class Detector {
 public:
  explicit Detector(const ModelIndex& index, const Limits& limits = Limits{});
  ~Detector();
  Detector(Detector&&) noexcept;
  Detector& operator=(Detector&&) noexcept;

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
  const std::vector<KeygraphMatch>& last_matches() const;
  // Scene keypoints (after sampling) of the last frame.
  const std::vector<Keypoint>& last_keypoints() const;
  const ModelIndex& index() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace kg
