// Tallies and files of `keygraph eval --truth` (eval/truth_eval.h): a
// table on stdout, truth-summary.json, truth-cases.csv (one row per method
// and truth instance, or per scene without any), truth-detections.csv (one
// row per detection, with its kind), truth-by-size.png (detection rate by
// the object's size, every method) and, with --gallery, gallery/METHOD/*.png.
#pragma once

#include <string>
#include <vector>

#include "eval/truth_eval.h"
#include "keygraph/status.h"

namespace kg {

struct TruthBin {
  double lo = 0, hi = 0;  // [lo, hi)
  int instances = 0, found = 0, found_iou = 0;
  double median_size = 0;  // of the instances in it (long edge or scale)
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

std::string truth_text(const std::vector<TruthRow>& rows, const TruthEvalOptions& options,
                       const TruthResults& results);

// Every file into `dir` (created if needed).
Status write_truth_report(const std::string& dir, const TruthEvalOptions& options,
                          const TruthResults& results);

}  // namespace kg
