// Tallies and files of `keygraph eval --truth` (eval/truth_eval.h): a
// table on stdout, truth-summary.json, truth-cases.csv (one row per method
// and truth instance, or per scene without any), truth-detections.csv (one
// row per detection, with its kind), truth-by-size.png (detection rate by
// the object's size, every method; the legend beside the axes) and, with
// --gallery, gallery/METHOD/*.png.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "eval/truth_eval.h"
#include "keygraph/status.h"

namespace kg {

struct TruthBin {
  double lo = 0, hi = 0;  // [lo, hi)
  int instances = 0, found = 0, found_iou = 0;
  double median_size = 0;  // of the instances in it (long edge or scale)
  // keygraph methods, at the ground-truth pose (TruthCase::truth_*):
  // instances measured, confirmable by the frame's keypoints, with at least
  // one and with enough correct correspondences; and why each measured
  // instance not found (IoU) was missed, in the pipeline's order: too few
  // model keypoints re-found to confirm the pose (keypoints), confirmable
  // but too few correct correspondences (correspondences), or both there
  // and the pose still not found (pose: RANSAC and its checks).
  int measured = 0, confirmable = 0, some_matches = 0, enough_matches = 0;
  int missed_keypoints = 0, missed_correspondences = 0, missed_pose = 0;
};

struct TruthRow {
  std::string method;
  int scenes = 0, instances = 0, found = 0, found_iou = 0;
  double median_corner_error = -1;  // of the found instances
  int negative_scenes = 0, negative_with_detections = 0;
  int detections = 0, wrong_identity = 0, false_detections = 0;
  // Homography truth: instances, and those whose grid error is within 2, 5, 10 px.
  int homography_instances = 0, within2 = 0, within5 = 0, within10 = 0;
  // keygraph methods: instances whose ground-truth pose was asked of the
  // verification (TruthCase::truth_*), those it could confirm, those of
  // them found, and the median model keypoints shown and re-found there.
  // truth_matched: instances with enough correct correspondences
  // (TruthCase::truth_enough_matches), alone and among the confirmable.
  int truth_measured = 0, truth_verifiable = 0, truth_verifiable_found = 0;
  int truth_matched = 0, truth_verifiable_matched = 0;
  double median_truth_shown = -1, median_truth_refound = -1;
  double median_ms = 0, p90_ms = 0;  // per scene
  std::vector<TruthBin> by_size;     // long edge in px
  std::vector<TruthBin> by_scale;    // relative to the model image
};

std::vector<TruthRow> truth_tallies(const TruthResults& results);

// The long-edge bins (px) of the tallies: 20-30, 30-40, 40-60, 60-100,
// 100-160, 160+ (issue 38), under 20, and the large ones of whole photos.
const std::vector<double>& truth_size_edges();

// truth-by-size.png: the fraction found by the object's long edge, a solid
// (corners) and a dashed (IoU) line per method, each method shifted a
// little along x with its own point markers (methods that find the same
// fraction stay visible), the legend beside the axes (never over the data).
// Every bin with instances is drawn as a step across its width with its
// marker at the bin's median size, so that a single bin is a visible
// segment, not a lone point; the x axis spans every such bin.
cv::Mat truth_size_plot(const std::vector<TruthRow>& rows);

std::string truth_text(const std::vector<TruthRow>& rows, const TruthEvalOptions& options,
                       const TruthResults& results);

// Checks, before any work, every file write_truth_report() may write into
// `dir` (platform/files/output_set.h: not an input, nothing in the way;
// with options.gallery, the gallery path of every scene for every method).
Status check_truth_report(const std::string& dir, const TruthEvalOptions& options,
                          const TruthResults& results);

// Every file into `dir` (created if needed), all or nothing; the gallery
// pictures are drawn here, one at a time, from the scene files. Gallery
// pictures of an earlier run that this one does not draw are removed
// (gallery/METHOD/NNNN_*.png; other files are left alone).
Status write_truth_report(const std::string& dir, const TruthEvalOptions& options,
                          const TruthResults& results);

// dir/gallery/METHOD/NNNN_STEM.png: scene NNNN (0-based, in manifest order).
std::string truth_gallery_path(const std::string& dir, const std::string& method, int scene,
                               const TruthResults& results);

}  // namespace kg
