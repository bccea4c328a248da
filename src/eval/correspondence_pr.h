// The paper's precision-recall measurement for one model against one scene
// (section 8): the true keypoint correspondences under the ground truth,
// the keygraph correspondences of a selection scored by their largest arc
// dissimilarity, and individual keypoints described by SIFT and selected by
// descriptor distance or by Lowe's ratio, all on the same model and scene
// keypoints.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "builder/model_builder.h"
#include "eval/pr_curves.h"
#include "keygraph/detector.h"
#include "keygraph/params.h"
#include "keygraph/types.h"

namespace kg {

// Keypoint correspondences (model keypoint m, scene keypoint s) that are
// correct: |truth(m) - s| < tolerance. Each gets an id 0..count()-1.
class CorrespondenceTruth {
 public:
  void build(const std::vector<Point2f>& model, const Keypoint* scene, int scene_count,
             const Homography& truth, double tolerance);
  long long count() const { return count_; }
  // Id of (m, s), or -1 when the pair is not correct (or out of range).
  long long id(std::uint32_t m, std::int32_t s) const;
  // The correct scene keypoints of model keypoint m, with their ids.
  struct Entry {
    std::int32_t scene = 0;
    long long id = 0;
  };
  const std::vector<Entry>& of(std::uint32_t m) const;
  // Scene keypoints that are part of a correct pair.
  bool scene_repeated(std::int32_t s) const;

 private:
  std::vector<std::vector<Entry>> by_model_;
  std::vector<bool> scene_repeated_;
  long long count_ = 0;
};

// Keygraph correspondences (model vertices: the model's own keypoint ids,
// i.e. global id minus ModelInfo::keypoint_begin) scored by the largest
// Euclidean distance between corresponding arc descriptors, the arcs of the
// structure's circuit ((0,1) for single arcs). `blurred` is the scene
// blurred as the detector blurs it (Params::descriptor.blur_sigma).
CaseCurve keygraph_curve(const BuiltModel& model, std::uint32_t keypoint_begin,
                         const cv::Mat& blurred, const Keypoint* scene, int scene_count,
                         const std::vector<KeygraphMatch>& matches, int model_id,
                         const Params& params, const CorrespondenceTruth& truth,
                         const std::vector<double>& thresholds);

// The scene blurred exactly as the core blurs it before arc profiles.
cv::Mat blur_for_descriptors(const cv::Mat& gray, float sigma);

// SIFT descriptors (builder/sift_descriptors.h, as vertex descriptors are
// computed) of keypoints, one float row each, scaled to unit length.
cv::Mat unit_sift(const cv::Mat& gray, const std::vector<Keypoint>& keypoints);

// Individual keypoints: every (m, s) pair selected when the SIFT distance
// is below the threshold (`by_distance`), and each model keypoint's nearest
// scene keypoint selected when nearest / second nearest distance is below
// the threshold (`by_ratio`, Lowe's ratio test).
void keypoint_curves(const cv::Mat& model_sift, const cv::Mat& scene_sift,
                     const CorrespondenceTruth& truth, const std::vector<double>& distance_grid,
                     const std::vector<double>& ratio_grid, CaseCurve& by_distance,
                     CaseCurve& by_ratio);

}  // namespace kg
