#include "eval/pr_curves.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace kg {

std::vector<double> threshold_grid(double lo, double hi, double step) {
  std::vector<double> out;
  if (!(step > 0) || !(hi >= lo)) return out;
  const auto n = static_cast<long long>(std::floor((hi - lo) / step + 1e-9));
  for (long long i = 0; i <= n; ++i) out.push_back(lo + static_cast<double>(i) * step);
  return out;
}

CurveBuilder::CurveBuilder(const std::vector<double>& thresholds, long long truth)
    : thresholds_(thresholds),
      truth_(std::max(0LL, truth)),
      selected_(thresholds.size() + 1, 0),
      correct_(thresholds.size() + 1, 0),
      reached_(static_cast<std::size_t>(truth_), std::numeric_limits<double>::infinity()) {}

int CurveBuilder::bin(double d) const {
  if (std::isnan(d)) return static_cast<int>(thresholds_.size());
  return static_cast<int>(std::lower_bound(thresholds_.begin(), thresholds_.end(), d) -
                          thresholds_.begin());
}

void CurveBuilder::add(double dissimilarity, bool correct) {
  const auto b = static_cast<std::size_t>(bin(dissimilarity));
  ++selected_[b];
  correct_[b] += correct;
}

void CurveBuilder::reach(long long truth_id, double dissimilarity) {
  if (truth_id < 0 || truth_id >= truth_) return;
  double& r = reached_[static_cast<std::size_t>(truth_id)];
  r = std::min(r, dissimilarity);
}

CaseCurve CurveBuilder::finish() const {
  CaseCurve c;
  c.truth = truth_;
  const std::size_t n = thresholds_.size();
  c.selected.assign(n, 0);
  c.correct.assign(n, 0);
  c.recalled.assign(n, 0);
  std::vector<long long> reached_bins(n + 1, 0);
  for (const double r : reached_) ++reached_bins[static_cast<std::size_t>(bin(r))];
  long long s = 0, k = 0, r = 0;
  for (std::size_t i = 0; i < n; ++i) {
    s += selected_[i];
    k += correct_[i];
    r += reached_bins[i];
    c.selected[i] = s;
    c.correct[i] = k;
    c.recalled[i] = r;
  }
  return c;
}

double expected_iterations(double precision, int h, double confidence) {
  if (!(precision > 0)) return std::numeric_limits<double>::infinity();
  if (precision >= 1) return 1.0;
  const double good = std::pow(precision, h);
  const double denom = std::log1p(-good);
  if (!(denom < 0)) return std::numeric_limits<double>::infinity();
  return std::max(1.0, std::log1p(-confidence) / denom);
}

double case_precision(const CaseCurve& c, std::size_t i) {
  if (i >= c.selected.size() || c.selected[i] == 0) return std::numeric_limits<double>::quiet_NaN();
  return static_cast<double>(c.correct[i]) / static_cast<double>(c.selected[i]);
}

double case_recall(const CaseCurve& c, std::size_t i) {
  if (i >= c.recalled.size() || c.truth == 0) return std::numeric_limits<double>::quiet_NaN();
  return static_cast<double>(c.recalled[i]) / static_cast<double>(c.truth);
}

MeanCurve mean_curve(const std::vector<double>& thresholds,
                     const std::vector<const CaseCurve*>& cases) {
  MeanCurve m;
  m.thresholds = thresholds;
  m.cases = static_cast<int>(cases.size());
  const std::size_t n = thresholds.size();
  m.recall.assign(n, 0.0);
  m.precision.assign(n, 0.0);
  m.recall_cases.assign(n, 0);
  m.precision_cases.assign(n, 0);
  for (const CaseCurve* c : cases) {
    for (std::size_t i = 0; i < n; ++i) {
      const double r = case_recall(*c, i), p = case_precision(*c, i);
      if (!std::isnan(r)) {
        m.recall[i] += r;
        ++m.recall_cases[i];
      }
      if (!std::isnan(p)) {
        m.precision[i] += p;
        ++m.precision_cases[i];
      }
    }
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < n; ++i) {
    m.recall[i] = m.recall_cases[i] > 0 ? m.recall[i] / m.recall_cases[i] : nan;
    m.precision[i] = m.precision_cases[i] > 0 ? m.precision[i] / m.precision_cases[i] : nan;
  }
  return m;
}

}  // namespace kg
