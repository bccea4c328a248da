// `keygraph eval --truth`: detectors scored against a ground-truth manifest
// (eval/truth_manifest.h, docs/EVAL.md) of real photos.
//
// Every method sees every scene, on one thread, with an index of the
// scene's "search" models (all models when the line has none). A truth
// instance is found when a detection of one of its acceptable models has
// all four corners within `tolerance` px in the best of the 8 corner
// orders, and separately when their quadrilaterals' IoU reaches `min_iou`.
// Each detection is a true one (the first to match an instance), a wrong
// identity (it lies on an instance, within the tolerance or the IoU, but
// names a model that instance does not accept) or a false one.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "builder/detector_settings.h"
#include "builder/progress.h"
#include "eval/truth_manifest.h"
#include "keygraph/params.h"
#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg {

struct TruthEvalOptions {
  std::string manifest;
  std::string models;  // a directory of model images or a models.json
  std::string index;   // or a built .kgi (keygraph methods only)
  // "keygraph", "keygraph-mser" and/or baseline names (eval/baselines.h).
  // Unless methods_set, with an index: keygraph alone (the others need
  // the model images).
  std::vector<std::string> methods = {"keygraph", "sift-magsac", "orb-magsac", "akaze-magsac"};
  bool methods_set = false;
  double tolerance = 10;  // px, every corner
  double min_iou = 0.5;
  Params params;              // for building the keygraph models
  bool params_set = false;    // --set given (not allowed with an index)
  DetectorSettings detector;  // the keygraph methods' threads and runtime options
  bool gallery = false;       // draw the scenes with a miss or a false detection
};

struct TruthModel {
  std::string name;
  int width = 0, height = 0;
};

// A detection in a scene, model pixels -> scene pixels.
struct FoundQuad {
  int model = -1;  // index into the evaluation's models
  Homography homography{};
  Point2f corners[4]{};
};

// A truth instance with its outline in the scene.
struct TruthQuad {
  std::vector<int> models;  // acceptable, indexes into the models
  Point2f corners[4]{};
  bool has_homography = false;
  Homography homography{};
};

enum class DetectionKind { kTrue, kWrongIdentity, kFalse };
const char* detection_kind_name(DetectionKind kind);

// One truth instance (or, for a scene without any, one row for the scene)
// as one method saw it.
struct TruthCase {
  std::string method;
  int scene = 0;             // index into the manifest's scenes
  int instance = -1;         // -1: the row of a scene without instances
  bool found = false;        // corners within the tolerance
  bool found_iou = false;    // IoU >= min_iou
  double corner_error = -1;  // best detection of an acceptable model, px; -1: none
  double iou = 0;            // best of those
  double long_edge = 0;      // longest side of the truth outline, px
  double scale = 0;          // sqrt(outline area / model image area)
  // Homography truth: median error of the model grid points inside the
  // scene under the best detection; -1: none or no truth homography.
  double homography_error = -1;
  int detections = 0, wrong_identity = 0, false_detections = 0;  // the scene's
  double time_ms = 0;                                            // the scene's, for this method
  // keygraph methods (Hessian keypoints on the frame as it is, or on the
  // frame upsampled 2x with keypoints.scene_upsample 2 or 3): the
  // instance's ground-truth pose asked of the detector's verification
  // (measure_pose_support(), core/pose/pose.h) over the frame's keypoints, for
  // the acceptable model and, without a truth homography, the corner order
  // that re-finds the most model keypoints. shown / refound -1: not
  // measured. verifiable: refound and z reach ransac.min_inliers and
  // min_verification_z, or the confirmed_* keypoint thresholds, or for an
  // outline of at most small_max_size px small_min_inliers (the last two
  // also ask the appearance): whether the frame's keypoints could confirm the
  // true pose at all; a miss where they could not is the keypoints', not
  // the search's or RANSAC's.
  // truth_matches: the keygraph correspondences of that model the
  // selection passed to RANSAC whose every vertex lies within
  // ransac.inlier_threshold of the true pose's image (-1: not measured);
  // truth_enough_matches: at least ransac.min_inlier_keygraphs of them,
  // what a pose needs.
  int truth_shown = -1, truth_refound = -1, truth_matches = -1;
  double truth_z = 0;
  bool truth_verifiable = false, truth_enough_matches = false;
};

struct TruthDetection {
  std::string method;
  int scene = 0;
  int model = -1;
  Point2f corners[4]{};
  DetectionKind kind = DetectionKind::kFalse;
  int instance = -1;  // the instance it lies on, if any
};

// A scene to draw into the gallery (with options.gallery): one with a
// missed instance or a wrong or false detection, for one method. Drawn when
// the report is written (truth_report.h), from the scene file and the
// results, so that memory does not grow with the gallery.
struct TruthGalleryEntry {
  std::string method;
  int scene = 0;
};

struct TruthResults {
  TruthManifest manifest;
  std::vector<TruthModel> models;
  std::vector<std::string> methods;
  std::vector<TruthCase> cases;
  std::vector<TruthDetection> detections;
  std::vector<TruthGalleryEntry> gallery;
  // Every file the evaluation reads (manifest, models.json, model images,
  // index, scenes): no output may be one of them.
  std::vector<std::string> inputs;
};

// The outline of a scene's truth instances in the scene (corners, or the
// model outline through the homography), acceptable models as indexes
// into results.models.
std::vector<TruthQuad> truth_quads(const TruthResults& results, int scene);

// Draws the scene: truth in green, true detections in blue, the others in
// red, each labelled (the gallery's pictures).
cv::Mat draw_truth_scene(const cv::Mat& gray, const std::vector<TruthQuad>& truth,
                         const std::vector<FoundQuad>& found,
                         const std::vector<DetectionKind>& kinds,
                         const std::vector<TruthModel>& models);

// Scores one scene for one method: fills found..iou, homography_error
// (scene_size: the scene's width and height) and the detections' kinds.
// `cases` gets one row per instance (one row when there is none).
void score_truth_scene(const std::vector<FoundQuad>& found, const std::vector<TruthQuad>& truth,
                       const std::vector<TruthModel>& models, int scene_width, int scene_height,
                       double tolerance, double min_iou, std::vector<TruthCase>& cases,
                       std::vector<DetectionKind>& kinds, std::vector<int>& instance_of);

// Checks everything (manifest, model names, scene files, methods) before
// the first model is built, then calls `before_work` (when given; the
// CLI checks its output paths against results.inputs there) and stops on
// its error; then the model images (sizes, outlines of homography truth)
// before the first detection: a bad input fails before any work. Scenes
// over kMaxBaselinePixels (eval/baselines.h) fail when a baseline method
// is to search them.
Status evaluate_truth(const TruthEvalOptions& options, TruthResults& results,
                      const ProgressFn& progress = {},
                      const std::function<Status(const TruthResults&)>& before_work = {});

}  // namespace kg
