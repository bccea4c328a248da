// The Oxford affine-region benchmark in the layout of the keygraph paper's
// experiments (<subset>/img1..6.png, H1to2p..H1to6p) and the evaluation of
// detection on it: models are crops of img1, scenes are img2..img6, the
// ground-truth pose is H1toN * T(crop offset).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "builder/detector_settings.h"
#include "builder/progress.h"
#include "eval/pr_curves.h"
#include "keygraph/params.h"
#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg {

// Reads a homography stored as 9 whitespace-separated numbers, row-major.
Status read_homography(const std::string& path, Homography& h);

struct OxfordEvalOptions {
  std::string dataset;               // directory holding the subsets
  std::vector<std::string> subsets;  // empty: every subdirectory with img1.png
  int crops_per_subset = 10;
  int crop_size = 300;
  bool centre_crop = false;  // one crop, centred, instead of random ones
  std::uint64_t seed = 1;
  Params params;
  DetectorSettings detector;  // the keygraph methods' threads and runtime options
  // "keygraph" (the index's keypoint detector, Hessian by default),
  // "keygraph-mser" (the same with MSER keypoints) and/or baseline names
  // (eval/baselines.h: "sift-ransac", ...).
  std::vector<std::string> methods = {"keygraph"};
  // Also run each crop against the scenes of the next subset (no instance
  // there): every detection on those is a false detection.
  bool negatives = false;
  // Precision-recall of correspondences for the keygraph methods (paper,
  // section 8): after the timed detection, the same scene runs through a
  // selection at the largest arc threshold of the grid (float32
  // descriptors, no pose search) and every keygraph correspondence is
  // scored; individual keypoints are the same model and scene keypoints
  // described by SIFT.
  bool curves = false;
  double curve_tolerance = 3.0;  // a keypoint correspondence is correct within this, px
};

// The thresholds that trace each curve.
struct OxfordCurveGrids {
  std::vector<double> arc;  // largest arc-descriptor distance of a keygraph correspondence
  std::vector<double> sift_distance;  // SIFT distance (unit descriptors)
  std::vector<double> sift_ratio;     // nearest / second-nearest SIFT distance
};
OxfordCurveGrids oxford_curve_grids();

struct OxfordCase {
  std::string method;
  std::string subset;
  bool negative = false;  // scene from another subset: any detection is false
  int crop = 0;
  int crop_x = 0, crop_y = 0;
  int degree = 0;            // scene imgN, N in 2..6
  std::string scene_subset;  // subset of the scene (differs for negatives)
  bool detected = false;
  double corner_error = -1;  // max over the 4 corners, pixels (first detection)
  int inliers = 0;
  int ransac_iterations = 0;
  int correspondences = 0;
  int first_ransac_iterations = 0;  // of the first detection's RANSAC attempt
  double time_ms = 0;
  // The image's own say on a pose, for any method: the normalised
  // cross-correlation of the crop (its appearance as an index stores it
  // by default, 128 px long edge) with the scene (blurred as the detector
  // blurs it) under the ground truth, on every positive case, and under
  // the first detection's pose; -1 on negative cases, without a detection,
  // and where it cannot be measured (core/pose/appearance_align.h: under 70 %
  // of the appearance inside the scene, a degenerate pose). keygraph's own
  // appearance refinement maximises this correlation, so its found value
  // is partly by construction; a method without one (SIFT) is the
  // independent check. A wrong pose that the image fits far better than
  // the ground truth is the ground truth's error, not the method's.
  double truth_correlation = -1;
  double found_correlation = -1;
  // With OxfordEvalOptions::curves, keygraph methods, positive scenes:
  bool has_curves = false;
  int model_keypoints = 0, scene_keypoints = 0;  // scene: after sampling
  // Repeatability: model keypoints that project inside the scene, and of
  // those the ones with a scene keypoint within curve_tolerance; scene
  // keypoints inside the crop's outline in the scene, and of those the ones
  // with a model keypoint within the tolerance.
  int model_inside = 0, model_repeated = 0, scene_inside = 0, scene_repeated = 0;
  bool curve_truncated = false;  // the curve selection hit a Limits capacity
  CaseCurve keygraph_curve, sift_distance_curve, sift_ratio_curve;
};

// Runs the evaluation; cases in subset, crop, degree order. `progress`
// (may be empty) is called after each case.
Status evaluate_oxford(const OxfordEvalOptions& options, std::vector<OxfordCase>& cases,
                       const ProgressFn& progress = {});

}  // namespace kg
