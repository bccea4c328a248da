// keygraph eval --dataset DIR | --synth DIR | --truth MANIFEST: the options
// of each mode are its Options table below (and in cmd_eval_truth.cpp);
// keygraph eval --help prints them.
//
// --dataset: the paper's second experiment on the Oxford layout: crops of
// img1 as models, img2..img6 as scenes; a detection succeeds when all four
// crop corners are within 3 (or 10) px of the ground truth. --curves adds
// the precision-recall of correspondences and the RANSAC iterations.
// --synth: the sign benchmark written by `keygraph synth` (--frames: the
// first N frames only).
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "builder/progress.h"
#include "cli/commands.h"
#include "cli/device/options.h"
#include "core/index/index_format.h"
#include "eval/baselines.h"
#include "eval/oxford.h"
#include "eval/oxford_report.h"
#include "eval/report_io.h"
#include "eval/synth_eval.h"
#include "eval/video_eval.h"
#include "keygraph/detector.h"
#include "keygraph/param_text.h"

namespace kg::cli {

namespace {

std::vector<std::string> split(const std::string& v) {
  std::vector<std::string> out;
  std::stringstream in(v);
  for (std::string s; std::getline(in, s, ',');) out.push_back(s);
  return out;
}

std::string joined(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& item : items) out += (out.empty() ? "" : ",") + item;
  return out;
}

}  // namespace

void declare_eval_settings(Options& options, Params& params, DetectorSettings& detector,
                           bool* params_set, const std::string& set_help) {
  options
      .value(
          "--set", "NAME=VALUE", set_help,
          [&params, &detector, params_set](const std::string& v) -> std::string {
            const std::size_t eq = v.find('=');
            std::string unused;
            if (eq != std::string::npos && !param_value_text(Params{}, v.substr(0, eq), unused)) {
              // Not a parameter of the index: a runtime option (checked
              // against the defaults: its range depends on no index).
              DetectOptions o;
              Status s = set_detect_option(o, v.substr(0, eq), v.substr(eq + 1));
              if (s) s = Detector::check_options(ModelIndex{}, o);
              if (!s)
                return "--set " + v + ": " + s.message() +
                       " (a parameter of keygraph/params.h, as keygraph inspect lists them, "
                       "or min_confidence, time_budget_ms, search_arcs_per_leaf, "
                       "ransac_barren_draws, align_min_ncc, align_coarse_min_ncc, "
                       "upsampled_min_confidence or upsampled_scene_keypoints)";
              detector.options.push_back(v);
              return {};
            }
            const Status s = set_param(params, v);
            if (!s) return s.message();
            // A runtime option stored in the index (ransac.*, the search
            // effort) also applies to an --index eval did not build.
            DetectOptions o;
            if (eq != std::string::npos &&
                set_detect_option(o, v.substr(0, eq), v.substr(eq + 1))) {
              detector.options.push_back(v);
            } else if (params_set != nullptr) {
              *params_set = true;
            }
            return {};
          })
      .repeatable()
      .integer("--threads", "N", detector.threads, 1, 64,
               "threads per detection of the keygraph methods, the caller's included (the\n"
               "detections are the same for any count)");
}

Options::Apply method_list_option(std::vector<std::string>& methods, bool* given) {
  return [&methods, given](const std::string& v) -> std::string {
    methods = method_list(v);
    if (methods.empty()) return "--methods is empty";
    for (const std::string& m : methods) {
      BaselineOptions baseline;
      if (m != "keygraph" && m != "keygraph-mser" && !parse_baseline(m, baseline))
        return "--methods: unknown method '" + m + "' (keygraph, keygraph-mser, " +
               joined(baseline_names()) + " or all)";
    }
    if (given != nullptr) *given = true;
    return {};
  };
}

namespace {

const char* const kSetHelp =
    "a parameter of keygraph/params.h, or a runtime option of the keygraph\n"
    "methods' detectors: min_confidence, time_budget_ms, search_arcs_per_leaf,\n"
    "ransac_barren_draws, align_min_ncc, align_coarse_min_ncc,\n"
    "upsampled_min_confidence, upsampled_scene_keypoints";

const char* const kQuietHelp =
    "no progress on stderr (by default one line rewritten in place on a\n"
    "terminal, otherwise a line every 10 %)";

const char* const kMethodsHelp =
    "keygraph, keygraph-mser and/or baselines (sift-ransac, ...); all: every one";

Options oxford_options(OxfordEvalOptions& o, std::string& out_dir, std::string& csv, bool& quiet) {
  Options options(
      "eval",
      "--dataset DIR [--subsets a,b] [--crops N] [--size S] [--centre] [--seed N]\n"
      "       [--set NAME=VALUE]... [--threads N] [--methods M,...|all] [--negatives]\n"
      "       [--curves] [-o DIR] [--csv FILE] [-q]",
      "The paper's second experiment on the Oxford layout: crops of img1 are the models,\n"
      "img2..img6 the scenes; a detection counts when its four corners are within 3\n"
      "(or 10) pixels of the ground truth.");
  options.text("--dataset", "DIR", o.dataset, "the Oxford-layout set (required)")
      .value("--subsets", "a,b,...", "the subsets to use (default: every one with img1)",
             [&o](const std::string& v) {
               o.subsets = split(v);
               return std::string();
             })
      .integer("--crops", "N", o.crops_per_subset, 1, 100000, "random crops of img1 per subset")
      .integer("--size", "S", o.crop_size, 32, Limits::kMaxSide, "crop side, pixels")
      .flag("--centre", o.centre_crop, "one crop, centred, instead of random ones")
      .unsigned64("--seed", "N", o.seed, "seed of the random crops")
      .value("--methods", "M,...|all", kMethodsHelp, method_list_option(o.methods, nullptr),
             joined(o.methods));
  declare_eval_settings(options, o.params, o.detector, nullptr, kSetHelp);
  options
      .flag("--negatives", o.negatives,
            "also run each crop on the next subset's scenes (false detections)")
      .flag("--curves", o.curves, "precision-recall of correspondences and RANSAC iterations")
      .text("-o, --out, --output", "DIR", out_dir, "also write the report (tables, plots) into DIR")
      .text("--csv", "FILE", csv, "also write every case to FILE")
      .flag("-q, --quiet", quiet, kQuietHelp)
      .example("keygraph eval --dataset ../shared/data/oxford --subsets graf,boat --methods all");
  return options;
}

Options synth_options(SynthEvalOptions& o, std::string& out_dir, bool& quiet) {
  Options options("eval",
                  "--synth DIR [--sizes 1,10,50] [--frames N] [--methods M,...|all]\n"
                  "       [--set NAME=VALUE]... [--threads N] [-o DIR] [-q]",
                  "The sign benchmark written by keygraph synth: each frame searched with indexes\n"
                  "of N signs; found within 10 pixels, false detections, time, by sign scale.");
  options.text("--synth", "DIR", o.directory, "the benchmark's directory (required)")
      .value(
          "--sizes", "N,...", "index sizes (signs per index; capped at the set's signs)",
          [&o](const std::string& v) -> std::string {
            o.index_sizes.clear();
            for (const std::string& n : split(v)) {
              int size = 0;
              if (!parse_int(n, 1, 100000, size))
                return "--sizes " + v + ": not a list of whole numbers in 1..100000";
              o.index_sizes.push_back(size);
            }
            if (o.index_sizes.empty()) return "--sizes is empty";
            return {};
          },
          [&o] {
            std::vector<std::string> sizes;
            for (const int n : o.index_sizes) sizes.push_back(std::to_string(n));
            return joined(sizes);
          }())
      .value(
          "--frames", "N", "the first N frames only, 1..1000000",
          [&o](const std::string& v) -> std::string {
            if (!parse_int(v, 1, 1000000, o.max_frames))
              return "--frames " + v + ": not a whole number in 1..1000000";
            return {};
          },
          "every frame")
      .value("--methods", "M,...|all", kMethodsHelp, method_list_option(o.methods, nullptr),
             joined(o.methods));
  declare_eval_settings(options, o.params, o.detector, nullptr, kSetHelp);
  options
      .text("-o, --out, --output", "DIR", out_dir, "also write the report (tables, plots) into DIR")
      .flag("-q, --quiet", quiet, kQuietHelp)
      .example("keygraph eval --synth signs-bench --sizes 1,50 --methods keygraph,sift-ransac");
  return options;
}

}  // namespace

int cmd_eval(const Args& args) {
  if (asks_for_help(args)) {
    // Every mode's options, whatever else is given.
    OxfordEvalOptions oxford;
    SynthEvalOptions synth;
    TruthEvalOptions truth;
    std::string out_dir, csv;
    bool quiet = false;
    std::fputs(oxford_options(oxford, out_dir, csv, quiet).help().c_str(), stdout);
    std::fputs(("\n" + synth_options(synth, out_dir, quiet).help()).c_str(), stdout);
    std::fputs(("\n" + truth_options(truth, out_dir, quiet).help()).c_str(), stdout);
    VideoEvalOptions video;
    bool json = false;
    std::fputs(("\n" + video_options(video, json, quiet).help()).c_str(), stdout);
    return 0;
  }
  for (const std::string& a : args) {
    if (a == "--truth") return cmd_eval_truth(args);  // cmd_eval_truth.cpp
    if (a == "--video") return cmd_eval_video(args);  // cmd_eval_video.cpp
  }
  OxfordEvalOptions options;
  SynthEvalOptions synth;
  std::string csv, out_dir;
  bool quiet = false;
  bool synth_mode = false, dataset_mode = false;
  for (const std::string& a : args) {
    synth_mode = synth_mode || a == "--synth";
    dataset_mode = dataset_mode || a == "--dataset";
  }
  const Options table = synth_mode ? synth_options(synth, out_dir, quiet)
                                   : oxford_options(options, out_dir, csv, quiet);
  if (synth_mode && dataset_mode)
    return table.usage_error("give one of --dataset DIR (Oxford layout) or --synth DIR");
  if (const int exit_code = table.parse(args); exit_code >= 0) return exit_code;
  if (options.dataset.empty() && synth.directory.empty())
    return table.usage_error(
        "give one of --dataset DIR (Oxford layout), --synth DIR (keygraph synth) or --truth "
        "MANIFEST");
  if (synth_mode) {
    options.params = synth.params;
    options.detector = synth.detector;
  }
  // Parameters out of range (--set) are the command line's fault.
  if (Status s = format::validate_params(options.params); !s) return table.usage_error(s.message());
  // The outputs before the (long) run, so that a bad one fails at once;
  // written all or nothing after it, never over a file of the data set.
  const std::vector<std::string> inputs =
      files_under(synth_mode ? synth.directory : options.dataset, 2);
  platform::OutputSet outputs(
      out_dir.empty() ? std::filesystem::path(csv).parent_path().string() : out_dir, inputs);
  if (!out_dir.empty()) {
    if (Status s = platform::check_output_directory(out_dir); !s)
      return fail("eval: --out " + s.message());
  }
  if (!csv.empty()) {
    if (Status s = outputs.check(csv); !s) return fail("eval: --csv " + s.message());
  }

  if (synth_mode) {
    std::vector<SynthCase> cases;
    ProgressReporter progress({"eval", "case", is_terminal(stderr), false},
                              quiet ? nullptr : stderr);
    Status s = evaluate_synth(synth, cases, progress.callback());
    progress.finish();
    if (!s) return fail(s.message());
    const std::vector<SynthRow> rows = synth_tallies(cases, synth);
    std::fputs(
        (synth_text(rows, synth_by_scale(cases, synth), synth_by_confidence(cases)) +
         synth_bins_text(synth_by_bins(cases, synth, SynthBinBy::kLongEdge),
                         SynthBinBy::kLongEdge) +
         synth_bins_text(synth_by_bins(cases, synth, SynthBinBy::kDistance), SynthBinBy::kDistance))
            .c_str(),
        stdout);
    if (!out_dir.empty()) {
      if (s = write_synth_report(outputs, out_dir, synth, cases); s) s = outputs.commit();
      if (!s) return fail("eval: " + s.message());
    }
    return 0;
  }

  std::vector<OxfordCase> cases;
  ProgressReporter progress({"eval", "case", is_terminal(stderr), false}, quiet ? nullptr : stderr);
  Status s = evaluate_oxford(options, cases, progress.callback());
  progress.finish();
  if (!s) return fail(s.message());
  const std::vector<OxfordRow> rows = oxford_tallies(cases, options.methods);
  std::fputs(
      oxford_text(rows, oxford_iterations(cases, options), oxford_limits(cases, options)).c_str(),
      stdout);
  std::fputs(oxford_wrong_poses_text(cases).c_str(), stdout);
  if (!out_dir.empty()) {
    if (s = write_oxford_report(outputs, out_dir, options, cases); !s)
      return fail("eval: " + s.message());
  }
  if (!csv.empty()) {
    std::ostringstream out;
    out << "method,subset,scene_subset,negative,crop,crop_x,crop_y,degree,detected,corner_error,"
           "inliers,correspondences,ransac_iterations,time_ms,truth_correlation,"
           "found_correlation\n";
    for (const OxfordCase& c : cases) {
      out << c.method << ',' << c.subset << ',' << c.scene_subset << ',' << c.negative << ','
          << c.crop << ',' << c.crop_x << ',' << c.crop_y << ',' << c.degree << ',' << c.detected
          << ',' << c.corner_error << ',' << c.inliers << ',' << c.correspondences << ','
          << c.ransac_iterations << ',' << c.time_ms << ',' << c.truth_correlation << ','
          << c.found_correlation << '\n';
    }
    if (s = outputs.add(csv, out.str()); !s) return fail("eval: " + s.message());
  }
  if (s = outputs.commit(); !s) return fail("eval: " + s.message());
  return 0;
}

}  // namespace kg::cli
