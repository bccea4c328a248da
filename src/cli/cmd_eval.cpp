// keygraph eval --dataset DIR [--subsets a,b] [--crops N] [--size S] [--centre]
//               [--seed N] [--set NAME=VALUE]... [--csv FILE]
// The paper's second experiment on the Oxford layout: crops of img1 as
// models, img2..img6 as scenes; a detection succeeds when all four crop
// corners are within 3 (or 10) px of the ground truth.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "build/oxford.h"
#include "build/param_overrides.h"
#include "cli/commands.h"
#include "core/index_format.h"

namespace kg::cli {

namespace {

struct Tally {
  int cases = 0, within3 = 0, within10 = 0, wrong = 0;
  std::vector<double> times;
  void add(const OxfordCase& c) {
    ++cases;
    within3 += c.detected && c.corner_error <= 3.0;
    within10 += c.detected && c.corner_error <= 10.0;
    wrong += c.detected && c.corner_error > 10.0;
    times.push_back(c.time_ms);
  }
  double median_ms() {
    if (times.empty()) return 0;
    std::sort(times.begin(), times.end());
    return times[times.size() / 2];
  }
};

void print_progress(const OxfordCase& c) {
  std::fprintf(stderr, "\r%-8s crop %2d img%d", c.subset.c_str(), c.crop, c.degree);
}

}  // namespace

int cmd_eval(const Args& args) {
  OxfordEvalOptions options;
  std::string csv;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--centre") {
      options.centre_crop = true;
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
  if (options.crops_per_subset < 1 || options.crop_size < 32)
    return fail("eval: bad --crops or --size");
  if (Status s = format::validate_params(options.params); !s) return fail("eval: " + s.message());

  std::vector<OxfordCase> cases;
  Status s = evaluate_oxford(options, cases, print_progress);
  std::fprintf(stderr, "\r%40s\r", "");
  if (!s) return fail(s.message());

  std::map<std::string, Tally> by_subset;
  std::map<int, Tally> by_degree;
  Tally all;
  for (const OxfordCase& c : cases) {
    by_subset[c.subset].add(c);
    by_degree[c.degree].add(c);
    all.add(c);
  }
  std::printf("%-10s %6s %8s %8s %6s %10s\n", "", "cases", "<=3px", "<=10px", "wrong", "median ms");
  auto row = [](const std::string& name, Tally& t) {
    std::printf("%-10s %6d %7.1f%% %7.1f%% %6d %10.1f\n", name.c_str(), t.cases,
                100.0 * t.within3 / t.cases, 100.0 * t.within10 / t.cases, t.wrong, t.median_ms());
  };
  for (auto& [name, t] : by_subset) row(name, t);
  for (auto& [degree, t] : by_degree) row("img" + std::to_string(degree), t);
  row("all", all);

  if (!csv.empty()) {
    const std::string tmp = csv + ".tmp";
    {
      std::ofstream out(tmp);
      out << "subset,crop,crop_x,crop_y,degree,detected,corner_error,inliers,correspondences,"
             "ransac_iterations,time_ms\n";
      for (const OxfordCase& c : cases) {
        out << c.subset << ',' << c.crop << ',' << c.crop_x << ',' << c.crop_y << ',' << c.degree
            << ',' << c.detected << ',' << c.corner_error << ',' << c.inliers << ','
            << c.correspondences << ',' << c.ransac_iterations << ',' << c.time_ms << '\n';
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
