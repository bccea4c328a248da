// Keypoint detector repeatability under a known homography (issue 4, item
// 2): of the keypoints detected in a model image that project inside the
// scene image, the fraction with a scene keypoint within `tolerance` pixels
// of their projection (centres only: no region overlap), and how many scene
// triangles could be correct keygraphs. Scene keypoints are sampled as the
// detector samples them (strongest first, Chebyshev 10 px) and triangulated
// (core Delaunay); a triangle inside the model's view counts as repeated
// when each vertex has a projected model keypoint within the tolerance, and
// as a keygraph when, besides, those three model keypoints are distinct and
// pairwise model arcs (GraphParams min..max Chebyshev distance): only such
// triangles can give a correct keygraph correspondence.
//
// Detectors: the core's Hessian and OpenCV's MSER centroids through
// KeypointExtractor (as the model builder runs them), and OpenCV's SIFT,
// ORB (2000 features) and AKAZE as the baselines create them. Every
// detector's keypoints are kept strongest first, at most
// Limits::max_keypoints, as Detector::detect() keeps them.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "keygraph/detector.h"
#include "keygraph/params.h"
#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg {

enum class RepeatabilityMethod { kHessian, kMser, kSift, kOrb, kAkaze };

// One detector to measure: "hessian", "mser", "sift", "orb", "akaze", the
// first two optionally with parameter settings for that row alone,
// "hessian:keypoints.hessian_threshold=0.0002:graph.scene_sample_distance=8";
// a name without a dot is short for keypoints.<detector>_<name>, so
// "hessian:threshold=0.0002:levels=2" and "mser:delta=8" work.
struct RepeatabilityDetector {
  std::string label;  // the text it was parsed from
  RepeatabilityMethod method = RepeatabilityMethod::kHessian;
  Params params;  // base parameters with the row's settings applied
};

// Parses a detector as above on top of `base` (the --set parameters);
// unknown names, settings on OpenCV's detectors and invalid parameters are
// errors.
Status parse_repeatability_detector(const std::string& text, const Params& base,
                                    RepeatabilityDetector& out);

// Runs one detector on 8-bit gray images.
class RepeatabilityKeypoints {
 public:
  explicit RepeatabilityKeypoints(const RepeatabilityDetector& detector);
  ~RepeatabilityKeypoints();
  RepeatabilityKeypoints(const RepeatabilityKeypoints&) = delete;
  RepeatabilityKeypoints& operator=(const RepeatabilityKeypoints&) = delete;

  // Clears `out` and fills it strongest first with at most max_keypoints.
  void detect(const cv::Mat& gray, int max_keypoints, std::vector<Keypoint>& out);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct RepeatabilityParams {
  double tolerance = 3.0;  // pixels, between a projected model keypoint and a scene keypoint
  // Offset (pixels, in x and in y) of the projection for the chance level:
  // the repeatability a detector of this density reaches under a wrong pose.
  float chance_shift = 15.f;
  float sample_distance = 10.f;                            // GraphParams::scene_sample_distance
  float min_arc = 10.f;                                    // GraphParams::min_distance
  float max_arc = 100.f;                                   // GraphParams::max_distance
  int max_scene_keypoints = Limits{}.max_scene_keypoints;  // after sampling
};

// Counts of one model image against one scene image.
struct PairRepeatability {
  int model_keypoints = 0;
  int scene_keypoints = 0;
  int model_inside = 0;    // model keypoints projecting inside the scene image
  int model_repeated = 0;  // of those, with a scene keypoint within the tolerance
  // The same for the projection shifted by chance_shift (chance level).
  int model_inside_shifted = 0, model_repeated_shifted = 0;
  int sampled = 0;           // scene keypoints after sampling
  int sampled_inside = 0;    // of those, inside the model image's view (inverse projection)
  int sampled_repeated = 0;  // of those, with a projected model keypoint within the tolerance
  // The same and triangles_keygraph for the sampled keypoints shifted by
  // chance_shift (their chance level; same denominators).
  int sampled_repeated_shifted = 0, triangles_keygraph_shifted = 0;
  int triangles = 0;           // scene triangles with all three vertices inside the model's view
  int triangles_repeated = 0;  // of those, all three vertices repeated
  int triangles_keygraph = 0;  // of those, the model counterparts form a model keygraph
};

// model_to_scene maps model pixels to scene pixels. Both keypoint lists
// strongest first (the scene's order decides the sampling).
PairRepeatability measure_repeatability(const std::vector<Keypoint>& model, cv::Size model_size,
                                        const std::vector<Keypoint>& scene, cv::Size scene_size,
                                        const Homography& model_to_scene,
                                        const RepeatabilityParams& params);

// The sampling and arc distances of `params` (graph.*), the scene keypoint
// limit of `limits`, and `tolerance`.
RepeatabilityParams repeatability_params(const Params& params, const Limits& limits,
                                         double tolerance);

// The Oxford layout: <dataset>/<subset>/img1..img6.png and H1to2p..H1to6p.
struct RepeatabilityOptions {
  std::string dataset;
  std::vector<std::string> subsets;  // empty: every subdirectory with img1.png, sorted
  // Each row's graph parameters give its sampling and arc distances.
  std::vector<RepeatabilityDetector> detectors;
  Limits limits;  // max_keypoints per image, max_scene_keypoints after sampling
  double tolerance = 3.0;
};

struct RepeatabilityCase {
  std::string detector;  // label
  std::string subset;
  int degree = 0;  // scene imgN, N in 2..6
  PairRepeatability counts;
};

// Detection of one image by one detector (img1..img6).
struct DetectionTiming {
  std::string detector;
  std::string subset;
  int image = 0;
  int pixels = 0;
  int keypoints = 0;
  double ms = 0;  // steady clock around the detector alone
};

// Runs every detector on every subset: cases in subset, detector, degree
// order; timings in subset, detector, image order. Times are wall-clock on
// whatever threads OpenCV uses: callers that report them call
// cv::setNumThreads(1) first. `progress` (may be null) is called after
// each detector's subset.
Status evaluate_repeatability(const RepeatabilityOptions& options,
                              std::vector<RepeatabilityCase>& cases,
                              std::vector<DetectionTiming>& timings,
                              void (*progress)(const std::string& detector,
                                               const std::string& subset) = nullptr);

}  // namespace kg
