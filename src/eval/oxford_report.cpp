#include "eval/oxford_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "eval/baselines.h"
#include "eval/plot.h"
#include "eval/report_io.h"

namespace kg {

namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

double median(std::vector<double> v) {
  if (v.empty()) return kNan;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

bool in_group(const OxfordCase& c, const std::string& group) {
  if (group == "all") return true;
  if (group.size() == 4 && group.rfind("img", 0) == 0)
    return !c.negative && c.degree == group[3] - '0';
  return c.subset == group;
}

// Subsets in order of appearance, then degrees, then "all".
std::vector<std::string> groups_of(const std::vector<OxfordCase>& cases) {
  std::vector<std::string> subsets;
  std::vector<int> degrees;
  for (const OxfordCase& c : cases) {
    if (std::find(subsets.begin(), subsets.end(), c.subset) == subsets.end())
      subsets.push_back(c.subset);
    if (!c.negative && std::find(degrees.begin(), degrees.end(), c.degree) == degrees.end())
      degrees.push_back(c.degree);
  }
  std::sort(degrees.begin(), degrees.end());
  std::vector<std::string> out = subsets;
  for (const int d : degrees) out.push_back("img" + std::to_string(d));
  out.push_back("all");
  return out;
}

std::vector<std::string> methods_of(const std::vector<OxfordCase>& cases) {
  std::vector<std::string> out;
  for (const OxfordCase& c : cases) {
    if (std::find(out.begin(), out.end(), c.method) == out.end()) out.push_back(c.method);
  }
  return out;
}

bool has_curves(const std::vector<OxfordCase>& cases, const std::string& method) {
  for (const OxfordCase& c : cases) {
    if (c.method == method && c.has_curves) return true;
  }
  return false;
}

std::size_t nearest(const std::vector<double>& grid, double v) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < grid.size(); ++i) {
    if (std::abs(grid[i] - v) < std::abs(grid[best] - v)) best = i;
  }
  return best;
}

int keygraph_sample_size(Structure s) {
  const int k = static_cast<int>(s);  // vertices; 4 keypoint correspondences make a homography
  return (4 + k - 1) / k;
}

std::string fmt(double v, const char* format = "%.1f") {
  if (std::isnan(v)) return "-";
  if (std::isinf(v)) return "inf";
  char buf[32];
  std::snprintf(buf, sizeof(buf), format, v);
  return buf;
}

std::string iterations_text(double v) {
  if (std::isnan(v)) return "-";
  if (std::isinf(v)) return "inf";
  char buf[32];
  std::snprintf(buf, sizeof(buf), v < 1e6 ? "%.0f" : "%.2g", v);
  return buf;
}

std::string csv_of(const MeanCurve& m, int h, double confidence) {
  std::ostringstream out;
  out << "threshold,recall,precision,expected_iterations,recall_cases,precision_cases\n";
  for (std::size_t i = 0; i < m.thresholds.size(); ++i) {
    const double e =
        std::isnan(m.precision[i]) ? kNan : expected_iterations(m.precision[i], h, confidence);
    out << json_value(m.thresholds[i]) << ','
        << (std::isnan(m.recall[i]) ? "" : json_value(m.recall[i])) << ','
        << (std::isnan(m.precision[i]) ? "" : json_value(m.precision[i])) << ','
        << (std::isnan(e)   ? ""
            : std::isinf(e) ? "inf"
                            : json_value(e))
        << ',' << m.recall_cases[i] << ',' << m.precision_cases[i] << '\n';
  }
  return out.str();
}

struct CurveSet {
  const MeanCurve* curve;
  std::string name, label, short_label;  // short: in the small panels
  int h;
  int marker;
  bool dashed;
};

std::vector<CurveSet> curve_sets(const OxfordCurves& c, const OxfordEvalOptions& options,
                                 const OxfordCurveGrids& grids) {
  const int h = keygraph_sample_size(options.params.graph.structure);
  const std::string vertices = std::to_string(static_cast<int>(options.params.graph.structure));
  return {
      {&c.keygraph, "keygraph", "keygraphs (" + vertices + "-vertex, arc Fourier)", "keygraphs", h,
       static_cast<int>(nearest(grids.arc, options.params.descriptor.similarity_threshold)), false},
      {&c.sift_distance, "sift-distance", "keypoints (SIFT, distance)", "SIFT distance", 4, -1,
       true},
      {&c.sift_ratio, "sift-ratio", "keypoints (SIFT, ratio test)", "SIFT ratio", 4,
       static_cast<int>(nearest(grids.sift_ratio, BaselineOptions{}.ratio)), false},
  };
}

cv::Mat pr_plot(const std::vector<CurveSet>& sets, const std::string& title, int w, int h) {
  PlotSpec spec;
  spec.title = title;
  spec.x_label = "recall";
  spec.y_label = "precision";
  spec.legend = LegendCorner::kTopRight;
  spec.width = w;
  spec.height = h;
  for (std::size_t i = 0; i < sets.size(); ++i) {
    PlotSeries s;
    s.label = w < 600 ? sets[i].short_label : sets[i].label;
    s.x = sets[i].curve->recall;
    s.y = sets[i].curve->precision;
    s.colour = plot_colour(static_cast<int>(i));
    s.dashed = sets[i].dashed;
    s.marker = sets[i].marker;
    spec.series.push_back(s);
  }
  return render_plot(spec);
}

cv::Mat iterations_plot(const std::vector<CurveSet>& sets, double confidence,
                        const std::string& title, int w, int h) {
  PlotSpec spec;
  spec.title = title;
  spec.x_label = "recall";
  spec.y_label = "expected RANSAC iterations";
  spec.log_y = true;
  spec.y_min = 1;
  spec.y_max = 1e8;
  spec.legend = LegendCorner::kTopLeft;
  spec.width = w;
  spec.height = h;
  for (std::size_t i = 0; i < sets.size(); ++i) {
    PlotSeries s;
    s.label =
        (w < 600 ? sets[i].short_label : sets[i].label) + ", h = " + std::to_string(sets[i].h);
    s.x = sets[i].curve->recall;
    for (const double p : sets[i].curve->precision)
      s.y.push_back(std::isnan(p) ? kNan : expected_iterations(p, sets[i].h, confidence));
    s.colour = plot_colour(static_cast<int>(i));
    s.dashed = sets[i].dashed;
    s.marker = sets[i].marker;
    spec.series.push_back(s);
  }
  return render_plot(spec);
}

}  // namespace

void OxfordTally::add(const OxfordCase& c) {
  times.push_back(c.time_ms);
  if (c.negative) {
    ++negatives;
    false_detections += c.detected;
    return;
  }
  ++cases;
  within3 += c.detected && c.corner_error <= 3.0;
  within10 += c.detected && c.corner_error <= 10.0;
  wrong += c.detected && c.corner_error > 10.0;
}

double OxfordTally::median_ms() const {
  return times.empty() ? 0.0 : median(times);
}

std::vector<OxfordRow> oxford_tallies(const std::vector<OxfordCase>& cases,
                                      const std::vector<std::string>& methods) {
  std::vector<OxfordRow> rows;
  const std::vector<std::string> groups = groups_of(cases);
  for (const std::string& method : methods) {
    for (const std::string& group : groups) {
      OxfordRow row{method, group, {}};
      for (const OxfordCase& c : cases) {
        if (c.method == method && in_group(c, group)) row.tally.add(c);
      }
      if (!row.tally.times.empty()) rows.push_back(std::move(row));
    }
  }
  return rows;
}

OxfordCurves oxford_mean_curves(const std::vector<OxfordCase>& cases, const std::string& method,
                                const std::string& group) {
  const OxfordCurveGrids grids = oxford_curve_grids();
  std::vector<const CaseCurve*> k, d, r;
  for (const OxfordCase& c : cases) {
    if (c.method != method || !c.has_curves || c.negative || !in_group(c, group)) continue;
    k.push_back(&c.keygraph_curve);
    d.push_back(&c.sift_distance_curve);
    r.push_back(&c.sift_ratio_curve);
  }
  return {mean_curve(grids.arc, k), mean_curve(grids.sift_distance, d),
          mean_curve(grids.sift_ratio, r)};
}

std::vector<OxfordIterationRow> oxford_iterations(const std::vector<OxfordCase>& cases,
                                                  const OxfordEvalOptions& options) {
  const OxfordCurveGrids grids = oxford_curve_grids();
  const double confidence = options.params.ransac.confidence;
  const std::size_t at = nearest(grids.arc, options.params.descriptor.similarity_threshold);
  const std::size_t ratio_at = nearest(grids.sift_ratio, BaselineOptions{}.ratio);
  std::vector<OxfordIterationRow> rows;
  for (const std::string& method : methods_of(cases)) {
    if (!has_curves(cases, method)) continue;
    for (const std::string& group : groups_of(cases)) {
      OxfordIterationRow row;
      row.method = method;
      row.group = group;
      row.arc_threshold = grids.arc[at];
      row.ratio = grids.sift_ratio[ratio_at];
      row.h_keygraph = keygraph_sample_size(options.params.graph.structure);
      std::vector<double> kg_expected, kp_expected, actual, first;
      for (const OxfordCase& c : cases) {
        if (c.method != method || !c.has_curves || c.negative || !in_group(c, group)) continue;
        ++row.cases;
        row.truncated += c.curve_truncated;
        const double p = case_precision(c.keygraph_curve, at);
        kg_expected.push_back(
            expected_iterations(std::isnan(p) ? 0.0 : p, row.h_keygraph, confidence));
        const double q = case_precision(c.sift_ratio_curve, ratio_at);
        kp_expected.push_back(
            expected_iterations(std::isnan(q) ? 0.0 : q, row.h_keypoint, confidence));
        actual.push_back(c.ransac_iterations);
        if (c.detected) first.push_back(c.first_ransac_iterations);
      }
      if (row.cases == 0) continue;
      const OxfordCurves m = oxford_mean_curves(cases, method, group);
      row.keygraph_precision = m.keygraph.precision[at];
      row.keygraph_recall = m.keygraph.recall[at];
      row.keygraph_expected =
          expected_iterations(row.keygraph_precision, row.h_keygraph, confidence);
      row.keygraph_expected_median = median(kg_expected);
      row.keypoint_precision = m.sift_ratio.precision[ratio_at];
      row.keypoint_recall = m.sift_ratio.recall[ratio_at];
      row.keypoint_expected =
          expected_iterations(row.keypoint_precision, row.h_keypoint, confidence);
      row.keypoint_expected_median = median(kp_expected);
      row.actual_median = median(actual);
      row.actual_first_median = median(first);
      rows.push_back(row);
    }
  }
  return rows;
}

std::vector<OxfordLimitRow> oxford_limits(const std::vector<OxfordCase>& cases,
                                          const OxfordEvalOptions& options) {
  const OxfordCurveGrids grids = oxford_curve_grids();
  const std::size_t at = nearest(grids.arc, options.params.descriptor.similarity_threshold);
  const long long need = options.params.ransac.min_inlier_keygraphs;
  std::vector<OxfordLimitRow> rows;
  for (const std::string& method : methods_of(cases)) {
    if (!has_curves(cases, method)) continue;
    for (const std::string& group : groups_of(cases)) {
      OxfordLimitRow row;
      row.method = method;
      row.group = group;
      int model_n = 0, scene_n = 0;
      std::vector<double> correct_found, correct_missed;
      for (const OxfordCase& c : cases) {
        if (c.method != method || !c.has_curves || c.negative || !in_group(c, group)) continue;
        ++row.cases;
        const bool found = c.detected && c.corner_error <= 10.0;
        const long long at_op = c.keygraph_curve.correct[at],
                        at_max = c.keygraph_curve.correct.back();
        (found ? correct_found : correct_missed).push_back(static_cast<double>(at_op));
        if (found) {
          ++row.found;
        } else if (at_max < need) {
          ++row.too_few_at_max;
        } else if (at_op < need) {
          ++row.threshold_limited;
        } else {
          ++row.pose_limited;
        }
        if (c.model_inside > 0) {
          row.model_repeatability += static_cast<double>(c.model_repeated) / c.model_inside;
          ++model_n;
        }
        if (c.scene_inside > 0) {
          const double r = static_cast<double>(c.scene_repeated) / c.scene_inside;
          row.scene_repeatability += r;
          row.scene_repeatability_cubed += r * r * r;
          ++scene_n;
        }
      }
      if (row.cases == 0) continue;
      row.model_repeatability = model_n > 0 ? row.model_repeatability / model_n : kNan;
      row.scene_repeatability = scene_n > 0 ? row.scene_repeatability / scene_n : kNan;
      row.scene_repeatability_cubed = scene_n > 0 ? row.scene_repeatability_cubed / scene_n : kNan;
      row.correct_found_median = median(correct_found);
      row.correct_missed_median = median(correct_missed);
      rows.push_back(row);
    }
  }
  return rows;
}

std::string oxford_text(const std::vector<OxfordRow>& rows,
                        const std::vector<OxfordIterationRow>& iterations,
                        const std::vector<OxfordLimitRow>& limits) {
  std::string out;
  char line[256];
  std::snprintf(line, sizeof(line), "%-13s %-8s %6s %8s %8s %6s %9s %10s\n", "method", "", "cases",
                "<=3px", "<=10px", "wrong", "false/neg", "median ms");
  out += line;
  for (const OxfordRow& r : rows) {
    const OxfordTally& t = r.tally;
    const double n = t.cases > 0 ? t.cases : 1;
    std::snprintf(line, sizeof(line), "%-13s %-8s %6d %7.1f%% %7.1f%% %6d %4d/%-4d %10.1f\n",
                  r.method.c_str(), r.group.c_str(), t.cases, 100.0 * t.within3 / n,
                  100.0 * t.within10 / n, t.wrong, t.false_detections, t.negatives, t.median_ms());
    out += line;
  }
  if (iterations.empty()) return out;
  out +=
      "\nRANSAC iterations: expected log(1-P)/log(1-p^h) from the precision p at the operating "
      "point, and run\n";
  std::snprintf(line, sizeof(line), "%-13s %-8s %5s | %-34s | %-34s | %-15s\n", "", "", "",
                "keygraphs at the arc threshold", "keypoints, SIFT ratio test", "run");
  out += line;
  std::snprintf(line, sizeof(line),
                "%-13s %-8s %5s | %6s %6s %9s %9s | %6s %6s %9s %9s | %7s %7s\n", "method", "",
                "cases", "prec", "recall", "expected", "median", "prec", "recall", "expected",
                "median", "frame", "found");
  out += line;
  for (const OxfordIterationRow& r : iterations) {
    std::snprintf(
        line, sizeof(line), "%-13s %-8s %5d | %6s %6s %9s %9s | %6s %6s %9s %9s | %7s %7s%s\n",
        r.method.c_str(), r.group.c_str(), r.cases, fmt(r.keygraph_precision, "%.3f").c_str(),
        fmt(r.keygraph_recall, "%.3f").c_str(), iterations_text(r.keygraph_expected).c_str(),
        iterations_text(r.keygraph_expected_median).c_str(),
        fmt(r.keypoint_precision, "%.3f").c_str(), fmt(r.keypoint_recall, "%.3f").c_str(),
        iterations_text(r.keypoint_expected).c_str(),
        iterations_text(r.keypoint_expected_median).c_str(),
        iterations_text(r.actual_median).c_str(), iterations_text(r.actual_first_median).c_str(),
        r.truncated > 0 ? " (some curves truncated)" : "");
    out += line;
  }
  if (limits.empty()) return out;
  out +=
      "\nWhere keygraphs lose the cases not found within 10 px (correct keygraph "
      "correspondences, <3 = fewer than RANSAC needs)\n";
  std::snprintf(line, sizeof(line), "%-13s %-8s %5s %5s | %8s %9s %6s | %7s %7s %7s | %8s %8s\n",
                "method", "", "cases", "found", "<3 @max", "<3 @index", "pose", "rep.m", "rep.s",
                "rep.s^3", "corr.fnd", "corr.mis");
  out += line;
  for (const OxfordLimitRow& r : limits) {
    std::snprintf(line, sizeof(line), "%-13s %-8s %5d %5d | %8d %9d %6d | %7s %7s %7s | %8s %8s\n",
                  r.method.c_str(), r.group.c_str(), r.cases, r.found, r.too_few_at_max,
                  r.threshold_limited, r.pose_limited, fmt(r.model_repeatability, "%.3f").c_str(),
                  fmt(r.scene_repeatability, "%.3f").c_str(),
                  fmt(r.scene_repeatability_cubed, "%.3f").c_str(),
                  fmt(r.correct_found_median, "%.0f").c_str(),
                  fmt(r.correct_missed_median, "%.0f").c_str());
    out += line;
  }
  return out;
}

std::string oxford_wrong_poses_text(const std::vector<OxfordCase>& cases) {
  std::string out;
  char line[256];
  for (const OxfordCase& c : cases) {
    if (c.negative || !c.detected || !(c.corner_error > 10.0)) continue;
    if (out.empty()) {
      out =
          "\nWrong poses (a corner more than 10 px from the ground truth), and the correlation of "
          "the crop\nwith the scene under the ground truth and under the pose found (-1: not "
          "measured):\n";
      std::snprintf(line, sizeof(line), "%-13s %-8s %5s %6s %9s %6s %6s\n", "method", "subset",
                    "crop", "scene", "corner px", "truth", "found");
      out += line;
    }
    std::snprintf(line, sizeof(line), "%-13s %-8s %5d %6s %9.1f %6.2f %6.2f\n", c.method.c_str(),
                  c.subset.c_str(), c.crop, ("img" + std::to_string(c.degree)).c_str(),
                  c.corner_error, c.truth_correlation, c.found_correlation);
    out += line;
  }
  return out;
}

Status write_oxford_report(platform::OutputSet& out, const std::string& dir,
                           const OxfordEvalOptions& options, const std::vector<OxfordCase>& cases) {
  Status s;
  const OxfordCurveGrids grids = oxford_curve_grids();
  const std::vector<std::string> methods = methods_of(cases);
  const std::vector<OxfordRow> rows = oxford_tallies(cases, methods);
  const std::vector<OxfordIterationRow> iterations = oxford_iterations(cases, options);
  const double confidence = options.params.ransac.confidence;

  // Cases.
  const std::size_t op = nearest(grids.arc, options.params.descriptor.similarity_threshold);
  std::ostringstream csv;
  csv << "method,subset,scene_subset,negative,crop,crop_x,crop_y,degree,detected,corner_error,"
         "inliers,correspondences,ransac_iterations,first_ransac_iterations,time_ms,"
         "model_keypoints,scene_keypoints,true_correspondences,model_inside,model_repeated,"
         "scene_inside,scene_repeated,keygraph_selected_at_index_threshold,"
         "keygraph_correct_at_index_threshold,keygraph_correct_at_max_threshold,"
         "keygraph_recalled_at_index_threshold,truth_correlation,found_correlation\n";
  for (const OxfordCase& c : cases) {
    csv << c.method << ',' << c.subset << ',' << c.scene_subset << ',' << c.negative << ','
        << c.crop << ',' << c.crop_x << ',' << c.crop_y << ',' << c.degree << ',' << c.detected
        << ',' << c.corner_error << ',' << c.inliers << ',' << c.correspondences << ','
        << c.ransac_iterations << ',' << c.first_ransac_iterations << ',' << c.time_ms << ','
        << c.model_keypoints << ',' << c.scene_keypoints << ','
        << (c.has_curves ? c.keygraph_curve.truth : -1) << ',' << c.model_inside << ','
        << c.model_repeated << ',' << c.scene_inside << ',' << c.scene_repeated << ',';
    if (c.has_curves) {
      const CaseCurve& k = c.keygraph_curve;
      csv << k.selected[op] << ',' << k.correct[op] << ',' << k.correct.back() << ','
          << k.recalled[op];
    } else {
      csv << ",,,";
    }
    csv << ',' << c.truth_correlation << ',' << c.found_correlation << '\n';
  }
  if (s = out.add(dir + "/cases.csv", csv.str()); !s) return s;

  // Curves and plots.
  std::string curve_json;
  for (const std::string& method : methods) {
    if (!has_curves(cases, method)) continue;
    std::vector<cv::Mat> pr_subsets, it_subsets, pr_degrees, it_degrees;
    for (const std::string& group : groups_of(cases)) {
      const OxfordCurves curves = oxford_mean_curves(cases, method, group);
      if (curves.keygraph.cases == 0) continue;
      const std::vector<CurveSet> sets = curve_sets(curves, options, grids);
      for (const CurveSet& set : sets) {
        const std::string file = "curves/" + method + "-" + group + "-" + set.name + ".csv";
        if (s = out.add(dir + "/" + file, csv_of(*set.curve, set.h, confidence)); !s) return s;
        curve_json += std::string(curve_json.empty() ? "" : ",\n") +
                      "    {\"method\": " + json_quote(method) +
                      ", \"group\": " + json_quote(group) + ", \"curve\": " + json_quote(set.name) +
                      ", \"h\": " + std::to_string(set.h) +
                      ", \"cases\": " + std::to_string(set.curve->cases) +
                      ", \"file\": " + json_quote(file) + "}";
      }
      const std::string title =
          method + ", " + group + " (" + std::to_string(curves.keygraph.cases) + " cases)";
      if (group == "all") {
        if (s = add_png(out, dir + "/pr-" + method + ".png", pr_plot(sets, title, 640, 480)); !s)
          return s;
        s = add_png(out, dir + "/iterations-" + method + ".png",
                    iterations_plot(sets, confidence, title, 640, 480));
        if (!s) return s;
      } else if (group.rfind("img", 0) == 0 && group.size() == 4) {
        pr_degrees.push_back(pr_plot(sets, title, 420, 330));
        it_degrees.push_back(iterations_plot(sets, confidence, title, 420, 330));
      } else {
        pr_subsets.push_back(pr_plot(sets, title, 420, 330));
        it_subsets.push_back(iterations_plot(sets, confidence, title, 420, 330));
      }
    }
    const std::pair<const char*, std::vector<cv::Mat>*> tiles[] = {
        {"pr-%s-subsets.png", &pr_subsets},
        {"iterations-%s-subsets.png", &it_subsets},
        {"pr-%s-degrees.png", &pr_degrees},
        {"iterations-%s-degrees.png", &it_degrees}};
    for (const auto& [pattern, panels] : tiles) {
      if (panels->empty()) continue;
      char name[128];
      std::snprintf(name, sizeof(name), pattern, method.c_str());
      if (s = add_png(out, dir + "/" + name, tile_plots(*panels, panels->size() > 6 ? 4 : 3)); !s)
        return s;
    }
  }

  // Summary.
  std::ostringstream j;
  j << "{\n  \"protocol\": \"oxford\",\n  \"dataset\": " << json_quote(options.dataset)
    << ",\n  \"crops_per_subset\": " << (options.centre_crop ? 1 : options.crops_per_subset)
    << ",\n  \"crop_size\": " << options.crop_size
    << ",\n  \"centre_crop\": " << (options.centre_crop ? "true" : "false")
    << ",\n  \"seed\": " << options.seed
    << ",\n  \"negatives\": " << (options.negatives ? "true" : "false")
    << ",\n  \"curve_tolerance_px\": " << json_value(options.curve_tolerance)
    << ",\n  \"ransac_confidence\": " << json_value(confidence) << ",\n  \"methods\": [";
  for (std::size_t i = 0; i < methods.size(); ++i) j << (i ? ", " : "") << json_quote(methods[i]);
  j << "],\n  \"detection\": [\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const OxfordTally& t = rows[i].tally;
    j << "    {\"method\": " << json_quote(rows[i].method)
      << ", \"group\": " << json_quote(rows[i].group) << ", \"cases\": " << t.cases
      << ", \"within_3px\": " << t.within3 << ", \"within_10px\": " << t.within10
      << ", \"wrong\": " << t.wrong << ", \"negatives\": " << t.negatives
      << ", \"false_detections\": " << t.false_detections
      << ", \"median_ms\": " << json_value(t.median_ms()) << "}"
      << (i + 1 < rows.size() ? ",\n" : "\n");
  }
  j << "  ],\n  \"iterations\": [\n";
  for (std::size_t i = 0; i < iterations.size(); ++i) {
    const OxfordIterationRow& r = iterations[i];
    j << "    {\"method\": " << json_quote(r.method) << ", \"group\": " << json_quote(r.group)
      << ", \"cases\": " << r.cases << ", \"arc_threshold\": " << json_value(r.arc_threshold)
      << ", \"ratio\": " << json_value(r.ratio) << ", \"h_keygraph\": " << r.h_keygraph
      << ", \"h_keypoint\": " << r.h_keypoint
      << ", \"keygraph_precision\": " << json_value(r.keygraph_precision)
      << ", \"keygraph_recall\": " << json_value(r.keygraph_recall)
      << ", \"keygraph_expected\": " << json_value(r.keygraph_expected)
      << ", \"keygraph_expected_median\": " << json_value(r.keygraph_expected_median)
      << ", \"keypoint_precision\": " << json_value(r.keypoint_precision)
      << ", \"keypoint_recall\": " << json_value(r.keypoint_recall)
      << ", \"keypoint_expected\": " << json_value(r.keypoint_expected)
      << ", \"keypoint_expected_median\": " << json_value(r.keypoint_expected_median)
      << ", \"run_median\": " << json_value(r.actual_median)
      << ", \"run_first_detection_median\": " << json_value(r.actual_first_median)
      << ", \"truncated_cases\": " << r.truncated << "}"
      << (i + 1 < iterations.size() ? ",\n" : "\n");
  }
  const std::vector<OxfordLimitRow> limits = oxford_limits(cases, options);
  j << "  ],\n  \"limits\": [\n";
  for (std::size_t i = 0; i < limits.size(); ++i) {
    const OxfordLimitRow& r = limits[i];
    j << "    {\"method\": " << json_quote(r.method) << ", \"group\": " << json_quote(r.group)
      << ", \"cases\": " << r.cases << ", \"found_10px\": " << r.found
      << ", \"too_few_correct_at_max_threshold\": " << r.too_few_at_max
      << ", \"too_few_correct_at_index_threshold\": " << r.threshold_limited
      << ", \"no_pose_despite_correct\": " << r.pose_limited
      << ", \"model_repeatability\": " << json_value(r.model_repeatability)
      << ", \"scene_repeatability\": " << json_value(r.scene_repeatability)
      << ", \"scene_repeatability_cubed\": " << json_value(r.scene_repeatability_cubed)
      << ", \"correct_at_index_threshold_found_median\": " << json_value(r.correct_found_median)
      << ", \"correct_at_index_threshold_missed_median\": " << json_value(r.correct_missed_median)
      << "}" << (i + 1 < limits.size() ? ",\n" : "\n");
  }
  j << "  ],\n  \"curves\": [\n" << curve_json << (curve_json.empty() ? "" : "\n") << "  ]\n}\n";
  return out.add(dir + "/summary.json", j.str());
}

}  // namespace kg
