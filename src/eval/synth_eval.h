// Scoring detectors on the synthetic sign benchmark (eval/synth/synth_set.h)
// with indexes of several sizes.
//
// For an index of N signs the catalogue is cut into groups of N
// consecutive signs; each frame is searched with the index of its sign's
// group (a sign-free frame with the groups in turn), so every frame counts
// once per index size. A frame's sign is found when a detection of that
// model has all four corners within 10 px (3 px for the stricter column) of
// the ground truth; every other detection is a false detection.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "builder/detector_settings.h"
#include "builder/progress.h"
#include "eval/synth/synth_frame.h"
#include "keygraph/detector.h"
#include "keygraph/params.h"
#include "keygraph/status.h"
#include "platform/files/output_set.h"

namespace kg {

struct SynthEvalOptions {
  std::string directory;                       // written by `keygraph synth`
  std::vector<int> index_sizes = {1, 10, 50};  // capped at the set's sign count
  // "keygraph", "keygraph-mser" and/or baseline names (eval/baselines.h).
  std::vector<std::string> methods = {"keygraph"};
  Params params;
  DetectorSettings detector;  // the keygraph methods' threads and runtime options
  int max_frames = 0;         // 0: every frame
};

// One detection as scored: right when of the frame's sign within 10 px.
struct SynthScoredDetection {
  int model = -1;
  bool right = false;
  double corner_error = -1;  // px, against the frame's sign (-1: another model)
  // The detector's support and confidence (a baseline's: inliers only).
  Detection support{};
};

struct SynthCase {
  std::string method;
  int index_size = 0;
  int group = 0;  // index of the group of signs searched
  int frame = 0;
  int sign = -1;             // the frame's sign, -1 for a sign-free frame
  bool found = false;        // within 10 px
  double corner_error = -1;  // max over the corners of the matching detection, px
  int detections = 0;
  int false_detections = 0;
  double time_ms = 0;  // scene side, the frame already in memory as gray
  // The frame's conditions (manifest): sign scale in the frame (square root
  // of its outline's area over the sign image's), hidden fraction, blur, noise.
  double scale = 0, occluded = 0, blur_sigma = 0, noise_sigma = 0;
  int motion_blur = 0;
  // The sign's longest side in the frame (px), its distance (m, range sets;
  // 0: not recorded), and the best IoU of a detection of its model with its
  // outline (found_iou: >= 0.5, the criterion for signs under 40 px).
  double long_edge = 0, distance = 0, iou = 0;
  bool found_iou = false;
  // Keygraph methods, frames with a sign: the detector's sampled keypoints
  // inside the sign's outline, and of those the ones within 3 px of a
  // model keypoint of the sign under the ground truth (-1: not measured).
  int sign_keypoints = -1, repeated_keypoints = -1;
  std::vector<SynthScoredDetection> scored{};  // every detection of the frame
  bool has_confidence = false;  // a keygraph method: its detections carry a confidence
};

// A detection of model `model` (an id within the searched index).
struct SynthDetection {
  int model = -1;
  Homography homography{};  // model pixels -> frame pixels
  // The detector's support and confidence (a baseline's: inliers only).
  Detection detail{};
};
// Scores one frame's detections against its ground truth: fills found,
// corner_error, detections, false_detections and scored of `c`. The index searched
// holds signs group_begin, group_begin + 1, ...; `sign_size` is the size of
// the frame's sign (unused for a sign-free frame).
void score_synth_frame(const std::vector<SynthDetection>& detections, const SynthFrameInfo& truth,
                       cv::Size sign_size, int group_begin, SynthCase& c);

// `progress` (may be empty) is called after each frame searched by a method.
Status evaluate_synth(const SynthEvalOptions& options, std::vector<SynthCase>& cases,
                      const ProgressFn& progress = {});

// Scores of one method at one index size.
struct SynthRow {
  std::string method;
  int index_size = 0;
  int frames = 0, sign_frames = 0, sign_free_frames = 0;
  int within3 = 0, within10 = 0;
  double median_corner_error = 0;  // of the found signs, px
  int false_detections = 0;
  int sign_free_with_false = 0;  // sign-free frames with any detection
  double median_ms = 0, mean_ms = 0;
};
std::vector<SynthRow> synth_tallies(const std::vector<SynthCase>& cases,
                                    const SynthEvalOptions& options);

// Found within 10 px per bucket of sign scale in the frame, per method, at
// one index size: the buckets' upper bounds and per method the counts.
struct SynthScaleRow {
  std::string method;
  int index_size = 0;
  std::vector<int> frames, found;  // per bucket
  std::vector<int> found_iou{};    // per bucket, IoU >= 0.5
  // Mean sign_keypoints and repeated_keypoints per bucket (NaN: none measured).
  std::vector<double> keypoints, repeated;
};
const std::vector<double>& synth_scale_buckets();  // upper bounds, last is infinity
std::vector<SynthScaleRow> synth_by_scale(const std::vector<SynthCase>& cases,
                                          const SynthEvalOptions& options);

// The same by the sign's long edge in the frame (px: 20-30, 30-40, 40-60,
// 60-100, 100-160, 160+, and under 20) and by its distance (range sets).
enum class SynthBinBy { kScale, kLongEdge, kDistance };
const std::vector<double>& synth_bin_bounds(SynthBinBy by);  // upper bounds
std::vector<SynthScaleRow> synth_by_bins(const std::vector<SynthCase>& cases,
                                         const SynthEvalOptions& options, SynthBinBy by);
// A table of found within 10 px and by IoU >= 0.5 per bin, every method;
// empty when no case has the quantity (distance of a set without it).
std::string synth_bins_text(const std::vector<SynthScaleRow>& rows, SynthBinBy by);

// Keygraph methods: signs found and false detections per frame when only
// the detections of confidence >= threshold are kept (Detection::confidence).
struct SynthConfidenceRow {
  std::string method;
  int index_size = 0;
  double threshold = 0;
  int frames = 0, sign_frames = 0;
  int found = 0;             // frames whose sign has a right detection kept
  int false_detections = 0;  // kept detections that are not right
};
const std::vector<double>& synth_confidence_thresholds();
std::vector<SynthConfidenceRow> synth_by_confidence(const std::vector<SynthCase>& cases);

std::string synth_text(const std::vector<SynthRow>& rows,
                       const std::vector<SynthScaleRow>& by_scale = {},
                       const std::vector<SynthConfidenceRow>& by_confidence = {});

// synth-summary.json, synth-cases.csv and synth-detections.csv in `dir`.
// Stages the report's files into `out` (its root `dir`, output_set.h); the
// caller commits: all or nothing.
Status write_synth_report(platform::OutputSet& out, const std::string& dir,
                          const SynthEvalOptions& options, const std::vector<SynthCase>& cases);

}  // namespace kg
