// keygraph eval --dataset DIR [--subsets a,b] [--crops N] [--size S] [--centre]
//               [--seed N] [--set NAME=VALUE]... [--methods m1,m2] [--negatives]
//               [--csv FILE]
// The paper's second experiment on the Oxford layout: crops of img1 as
// models, img2..img6 as scenes; a detection succeeds when all four crop
// corners are within 3 (or 10) px of the ground truth.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "build/baselines.h"
#include "build/oxford.h"
#include "build/param_overrides.h"
#include "cli/commands.h"
#include "core/index_format.h"

namespace kg::cli {

namespace {

struct Tally {
  int cases = 0, within3 = 0, within10 = 0, wrong = 0;
  int negatives = 0, false_detections = 0;
  std::vector<double> times;
  void add(const OxfordCase& c) {
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
  double median_ms() {
    if (times.empty()) return 0;
    std::sort(times.begin(), times.end());
    return times[times.size() / 2];
  }
};

void print_progress(const OxfordCase& c) {
  std::fprintf(stderr, "\r%-12s %-8s crop %2d img%d", c.method.c_str(), c.subset.c_str(), c.crop,
               c.degree);
}

}  // namespace

int cmd_eval(const Args& args) {
  OxfordEvalOptions options;
  std::string csv;
  std::vector<std::string> methods;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--centre" || a == "--negatives") {
      (a == "--centre" ? options.centre_crop : options.negatives) = true;
      continue;
    }
    if (i + 1 >= args.size()) return fail("eval: " + a + " needs a value (or is unknown)");
    const std::string& v = args[++i];
    try {
      if (a == "--dataset") {
        options.dataset = v;
      } else if (a == "--subsets") {
        std::stringstream in(v);
        for (std::string s; std::getline(in, s, ',');) options.subsets.push_back(s);
      } else if (a == "--crops") {
        options.crops_per_subset = std::stoi(v);
      } else if (a == "--size") {
        options.crop_size = std::stoi(v);
      } else if (a == "--seed") {
        options.seed = std::stoull(v);
      } else if (a == "--set") {
        Status s = apply_param_override(v, options.params);
        if (!s) return fail("eval: " + s.message());
      } else if (a == "--methods") {
        std::stringstream in(v);
        for (std::string m; std::getline(in, m, ',');) methods.push_back(m == "all" ? "" : m);
      } else if (a == "--csv") {
        csv = v;
      } else {
        return fail("eval: unknown option " + a);
      }
    } catch (const std::exception&) {
      return fail("eval: bad number '" + v + "' for " + a);
    }
  }
  if (options.dataset.empty()) return fail("eval: no dataset given (--dataset DIR)");
  if (!methods.empty()) {
    options.methods.clear();
    for (const std::string& m : methods) {
      if (!m.empty()) {
        options.methods.push_back(m);
        continue;
      }
      options.methods.push_back("keygraph");  // "all": keygraph and every baseline
      for (const std::string& b : baseline_names()) options.methods.push_back(b);
    }
  }
  if (options.crops_per_subset < 1 || options.crop_size < 32)
    return fail("eval: bad --crops or --size");
  if (Status s = format::validate_params(options.params); !s) return fail("eval: " + s.message());

  std::vector<OxfordCase> cases;
  Status s = evaluate_oxford(options, cases, print_progress);
  std::fprintf(stderr, "\r%40s\r", "");
  if (!s) return fail(s.message());

  std::printf("%-13s %-8s %6s %8s %8s %6s %9s %10s\n", "method", "", "cases", "<=3px", "<=10px",
              "wrong", "false/neg", "median ms");
  auto row = [](const std::string& method, const std::string& name, Tally& t) {
    const double n = t.cases > 0 ? t.cases : 1;
    std::printf("%-13s %-8s %6d %7.1f%% %7.1f%% %6d %4d/%-4d %10.1f\n", method.c_str(),
                name.c_str(), t.cases, 100.0 * t.within3 / n, 100.0 * t.within10 / n, t.wrong,
                t.false_detections, t.negatives, t.median_ms());
  };
  for (const std::string& method : options.methods) {
    std::map<std::string, Tally> by_subset;
    std::map<int, Tally> by_degree;
    Tally all;
    for (const OxfordCase& c : cases) {
      if (c.method != method) continue;
      by_subset[c.subset].add(c);
      if (!c.negative) by_degree[c.degree].add(c);
      all.add(c);
    }
    for (auto& [name, t] : by_subset) row(method, name, t);
    for (auto& [degree, t] : by_degree) row(method, "img" + std::to_string(degree), t);
    row(method, "all", all);
  }

  if (!csv.empty()) {
    const std::string tmp = csv + ".tmp";
    {
      std::ofstream out(tmp);
      out << "method,subset,scene_subset,negative,crop,crop_x,crop_y,degree,detected,corner_error,"
             "inliers,correspondences,ransac_iterations,time_ms\n";
      for (const OxfordCase& c : cases) {
        out << c.method << ',' << c.subset << ',' << c.scene_subset << ',' << c.negative << ','
            << c.crop << ',' << c.crop_x << ',' << c.crop_y << ',' << c.degree << ',' << c.detected
            << ',' << c.corner_error << ',' << c.inliers << ',' << c.correspondences << ','
            << c.ransac_iterations << ',' << c.time_ms << '\n';
      }
      if (!out) {
        std::remove(tmp.c_str());
        return fail("eval: cannot write " + csv);
      }
    }
    if (std::rename(tmp.c_str(), csv.c_str()) != 0) {
      std::remove(tmp.c_str());
      return fail("eval: cannot write " + csv);
    }
  }
  return 0;
}

}  // namespace kg::cli
