// Precision-recall of correspondences, as the keygraph paper measures it
// (section 8): a curve is traced by a dissimilarity threshold; precision is
// the fraction of the selected correspondences that are correct, recall the
// fraction of the correct keypoint correspondences that the selection
// reaches. For keygraphs the selected items are keygraph correspondences (a
// keygraph correspondence is correct when all keypoint correspondences it
// implies are) while recall is always counted in keypoint correspondences,
// the ones the selected keygraph correspondences imply, so keygraphs and
// individual keypoints share one recall axis.
//
// And the RANSAC iterations such a precision p implies: log(1 - P) /
// log(1 - p^h), h the sample size (2 keygraph correspondences of 3-circuits,
// 4 keypoint correspondences for a homography).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace kg {

// Thresholds lo, lo + step, ..., up to hi inclusive.
std::vector<double> threshold_grid(double lo, double hi, double step);

// Counts of one case (one model against one scene) at each threshold.
struct CaseCurve {
  long long truth = 0;              // correct keypoint correspondences that exist
  std::vector<long long> selected;  // items selected at threshold i
  std::vector<long long> correct;   // of those, correct
  std::vector<long long> recalled;  // distinct true keypoint correspondences they reach
};

// Accumulates one case: every candidate item with its dissimilarity (it is
// selected at every threshold >= that), and for each true keypoint
// correspondence (ids 0..truth-1) the dissimilarities of the items that
// reach it (the smallest counts).
class CurveBuilder {
 public:
  CurveBuilder(const std::vector<double>& thresholds, long long truth);
  void add(double dissimilarity, bool correct);
  void reach(long long truth_id, double dissimilarity);
  CaseCurve finish() const;

 private:
  int bin(double dissimilarity) const;  // first threshold >= d; size() when none
  std::vector<double> thresholds_;
  long long truth_;
  std::vector<long long> selected_, correct_;
  std::vector<double> reached_;  // per true correspondence, smallest dissimilarity
};

// log(1 - confidence) / log(1 - p^h), uncapped: infinity for p = 0, 1 for p = 1.
double expected_iterations(double precision, int h, double confidence);

// The mean of cases' curves (paper: "each curve is the mean of the curves
// across all pairs"): at each threshold, recall averaged over the cases that
// have true correspondences, precision over the cases that select anything.
struct MeanCurve {
  std::vector<double> thresholds;
  std::vector<double> recall;     // NaN where no case has true correspondences
  std::vector<double> precision;  // NaN where no case selects anything
  std::vector<int> recall_cases, precision_cases;
  int cases = 0;
};
MeanCurve mean_curve(const std::vector<double>& thresholds,
                     const std::vector<const CaseCurve*>& cases);

// The point of a case's curve at a threshold (index into the grid).
double case_precision(const CaseCurve& c, std::size_t i);  // NaN when nothing selected
double case_recall(const CaseCurve& c, std::size_t i);     // NaN when truth == 0

}  // namespace kg
