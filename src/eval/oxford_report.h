// Tables, curves and plots of an Oxford evaluation (eval/oxford.h): per
// method, per subset, per degree (scene img2..img6) and overall.
//
// Output directory layout (write_oxford_report):
//   summary.json                    options, tables, iteration table, curve files
//   cases.csv                       one row per case
//   curves/<method>-<group>-<curve>.csv   threshold, recall, precision, expected
//                                   iterations (curve: keygraph, sift-distance, sift-ratio)
//   pr-<method>.png, iterations-<method>.png               overall
//   pr-<method>-subsets.png, iterations-<method>-subsets.png  one panel per subset
//   pr-<method>-degrees.png, iterations-<method>-degrees.png  one panel per degree
#pragma once

#include <string>
#include <vector>

#include "eval/oxford.h"
#include "eval/pr_curves.h"
#include "platform/files/output_set.h"

namespace kg {

struct OxfordTally {
  int cases = 0, within3 = 0, within10 = 0, wrong = 0;
  int negatives = 0, false_detections = 0;
  std::vector<double> times;  // every case, positives and negatives
  void add(const OxfordCase& c);
  double median_ms() const;
};

// Group names: the subsets, "img2".."img6" (positive cases by degree), "all".
struct OxfordRow {
  std::string method, group;
  OxfordTally tally;
};
std::vector<OxfordRow> oxford_tallies(const std::vector<OxfordCase>& cases,
                                      const std::vector<std::string>& methods);

// RANSAC iterations, expected from precision and actually run, per group of
// a keygraph method with curves. The operating points are the index's arc
// threshold (keygraph correspondences, h = ceil(4 / vertices)) and the
// baselines' ratio test (SIFT keypoints, h = 4).
struct OxfordIterationRow {
  std::string method, group;
  int cases = 0;
  double arc_threshold = 0, ratio = 0;
  int h_keygraph = 2, h_keypoint = 4;
  double keygraph_precision = 0, keygraph_recall = 0;  // mean curves at the operating point
  double keygraph_expected = 0;                        // from the mean precision
  double keygraph_expected_median = 0;  // median over cases of each case's expectation
  double keypoint_precision = 0, keypoint_recall = 0;
  double keypoint_expected = 0, keypoint_expected_median = 0;
  double actual_median = 0;        // RANSAC iterations per frame (all attempts), median
  double actual_first_median = 0;  // of the first detection's attempt, detected cases
  int truncated = 0;               // cases whose curve selection hit a capacity
};
std::vector<OxfordIterationRow> oxford_iterations(const std::vector<OxfordCase>& cases,
                                                  const OxfordEvalOptions& options);

// What stops keygraphs, per group of a keygraph method with curves: the
// positive cases not found within 10 px split by where the pipeline lost
// them (min_inlier_keygraphs correct keygraph correspondences are needed):
// too few correct ones even at the grid's largest arc threshold (keypoints
// not repeated, or their arcs too unlike), enough there but not at the
// index's threshold (the descriptor threshold), or enough at the index's
// threshold and still no pose (RANSAC, refinement, verification). With the
// mean keypoint repeatability both ways and its cube for the scene side
// (the chance that a scene triangle has three repeated corners).
struct OxfordLimitRow {
  std::string method, group;
  int cases = 0, found = 0;
  int too_few_at_max = 0, threshold_limited = 0, pose_limited = 0;
  double model_repeatability = 0, scene_repeatability = 0, scene_repeatability_cubed = 0;
  double correct_found_median = 0, correct_missed_median = 0;  // correct at the index's threshold
};
std::vector<OxfordLimitRow> oxford_limits(const std::vector<OxfordCase>& cases,
                                          const OxfordEvalOptions& options);

// The mean curves of one method and group (empty when it has no curves).
struct OxfordCurves {
  MeanCurve keygraph, sift_distance, sift_ratio;
};
OxfordCurves oxford_mean_curves(const std::vector<OxfordCase>& cases, const std::string& method,
                                const std::string& group);

// The tables as printed by `keygraph eval`.
std::string oxford_text(const std::vector<OxfordRow>& rows,
                        const std::vector<OxfordIterationRow>& iterations,
                        const std::vector<OxfordLimitRow>& limits = {});

// One line per wrong pose (positive scene, a corner more than 10 px off)
// with OxfordCase::truth_correlation and found_correlation; empty when
// there is none.
std::string oxford_wrong_poses_text(const std::vector<OxfordCase>& cases);

// Stages the report's files into `out` (its root `dir`, output_set.h); the
// caller commits: all or nothing.
Status write_oxford_report(platform::OutputSet& out, const std::string& dir,
                           const OxfordEvalOptions& options, const std::vector<OxfordCase>& cases);

}  // namespace kg
