// keygraph eval --dataset DIR [--subsets a,b] [--crops N] [--size S] [--centre]
//               [--seed N] [--set NAME=VALUE]... [--methods m1,m2|all] [--negatives]
//               [--curves] [--out DIR] [--csv FILE]
// keygraph eval --truth MANIFEST ...: see cmd_eval_truth.cpp.
// keygraph eval --synth DIR [--sizes 1,10,50] [--frames N] [--methods ...] [--set ...]
//               [--out DIR]
//
// --dataset: the paper's second experiment on the Oxford layout: crops of
// img1 as models, img2..img6 as scenes; a detection succeeds when all four
// crop corners are within 3 (or 10) px of the ground truth. --curves adds
// the precision-recall of correspondences and the RANSAC iterations.
// --synth: the sign benchmark written by `keygraph synth` (--frames: the
// first N frames only).
#include <cstdio>
#include <sstream>

#include "build/baselines.h"
#include "build/oxford.h"
#include "build/oxford_report.h"
#include "build/param_overrides.h"
#include "build/report_io.h"
#include "build/synth_eval.h"
#include "cli/commands.h"
#include "core/index_format.h"

namespace kg::cli {

namespace {

bool progress_shown = false;

// Clears the progress line, if any, before results or an error.
void clear_progress() {
  if (progress_shown) std::fprintf(stderr, "\r%60s\r", "");
  progress_shown = false;
}

void print_oxford_progress(const OxfordCase& c) {
  progress_shown = true;
  std::fprintf(stderr, "\r%-13s %-8s crop %2d img%d %s", c.method.c_str(), c.subset.c_str(), c.crop,
               c.degree, c.negative ? "(negative)" : "          ");
}

void print_synth_progress(const SynthCase& c) {
  progress_shown = true;
  std::fprintf(stderr, "\r%-13s index of %2d  frame %4d", c.method.c_str(), c.index_size, c.frame);
}

std::vector<std::string> split(const std::string& v) {
  std::vector<std::string> out;
  std::stringstream in(v);
  for (std::string s; std::getline(in, s, ',');) out.push_back(s);
  return out;
}

}  // namespace

int cmd_eval(const Args& args) {
  for (const std::string& a : args) {
    if (a == "--truth") return cmd_eval_truth(args);  // cmd_eval_truth.cpp
  }
  OxfordEvalOptions options;
  SynthEvalOptions synth;
  std::string csv, out_dir;
  std::vector<std::string> methods;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--centre" || a == "--negatives" || a == "--curves") {
      (a == "--centre"      ? options.centre_crop
       : a == "--negatives" ? options.negatives
                            : options.curves) = true;
      continue;
    }
    if (i + 1 >= args.size()) return fail("eval: " + a + " needs a value (or is unknown)");
    const std::string& v = args[++i];
    try {
      if (a == "--dataset") {
        options.dataset = v;
      } else if (a == "--synth") {
        synth.directory = v;
      } else if (a == "--subsets") {
        options.subsets = split(v);
      } else if (a == "--crops") {
        options.crops_per_subset = std::stoi(v);
      } else if (a == "--size") {
        options.crop_size = std::stoi(v);
      } else if (a == "--seed") {
        options.seed = std::stoull(v);
      } else if (a == "--sizes") {
        synth.index_sizes.clear();
        for (const std::string& n : split(v)) synth.index_sizes.push_back(std::stoi(n));
      } else if (a == "--frames") {
        synth.max_frames = std::stoi(v);
      } else if (a == "--set") {
        Status s = apply_param_override(v, options.params);
        if (!s) return fail("eval: " + s.message());
      } else if (a == "--methods") {
        methods = method_list(v);
      } else if (a == "--csv") {
        csv = v;
      } else if (a == "--out") {
        out_dir = v;
      } else {
        return fail("eval: unknown option " + a);
      }
    } catch (const std::exception&) {
      return fail("eval: bad number '" + v + "' for " + a);
    }
  }
  if (options.dataset.empty() == synth.directory.empty())
    return fail("eval: give one of --dataset DIR (Oxford layout) or --synth DIR (keygraph synth)");
  if (Status s = format::validate_params(options.params); !s) return fail("eval: " + s.message());
  // The output directory before the (long) run, so that a bad one fails at once.
  if (!out_dir.empty()) {
    if (Status s = ensure_directory(out_dir); !s) return fail("eval: " + s.message());
  }

  if (!synth.directory.empty()) {
    synth.params = options.params;
    if (!methods.empty()) synth.methods = methods;
    for (const int n : synth.index_sizes) {
      if (n < 1) return fail("eval: bad --sizes");
    }
    std::vector<SynthCase> cases;
    Status s = evaluate_synth(synth, cases, print_synth_progress);
    clear_progress();
    if (!s) return fail(s.message());
    const std::vector<SynthRow> rows = synth_tallies(cases, synth);
    std::fputs(synth_text(rows, synth_by_scale(cases, synth), synth_by_confidence(cases)).c_str(),
               stdout);
    if (!out_dir.empty()) {
      if (s = write_synth_report(out_dir, synth, cases); !s) return fail("eval: " + s.message());
    }
    return 0;
  }

  if (!methods.empty()) options.methods = methods;
  if (options.crops_per_subset < 1 || options.crop_size < 32)
    return fail("eval: bad --crops or --size");
  std::vector<OxfordCase> cases;
  Status s = evaluate_oxford(options, cases, print_oxford_progress);
  clear_progress();
  if (!s) return fail(s.message());
  const std::vector<OxfordRow> rows = oxford_tallies(cases, options.methods);
  std::fputs(
      oxford_text(rows, oxford_iterations(cases, options), oxford_limits(cases, options)).c_str(),
      stdout);
  if (!out_dir.empty()) {
    if (s = write_oxford_report(out_dir, options, cases); !s) return fail("eval: " + s.message());
  }
  if (!csv.empty()) {
    std::ostringstream out;
    out << "method,subset,scene_subset,negative,crop,crop_x,crop_y,degree,detected,corner_error,"
           "inliers,correspondences,ransac_iterations,time_ms\n";
    for (const OxfordCase& c : cases) {
      out << c.method << ',' << c.subset << ',' << c.scene_subset << ',' << c.negative << ','
          << c.crop << ',' << c.crop_x << ',' << c.crop_y << ',' << c.degree << ',' << c.detected
          << ',' << c.corner_error << ',' << c.inliers << ',' << c.correspondences << ','
          << c.ransac_iterations << ',' << c.time_ms << '\n';
    }
    if (s = write_text_file(csv, out.str()); !s) return fail("eval: " + s.message());
  }
  return 0;
}

}  // namespace kg::cli
