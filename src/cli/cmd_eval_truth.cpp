// keygraph eval --truth: its options are the Options table below (keygraph eval --help).
//
// Detectors scored against a ground-truth manifest (docs/EVAL.md): the
// table on stdout, the files of eval/truth_report.h in --out. Every input
// is checked before the first detection, and nothing is written unless the
// whole run succeeds.
#include <cstdio>

#include "builder/progress.h"
#include "cli/commands.h"
#include "cli/device/options.h"
#include "core/index/index_format.h"
#include "eval/baselines.h"
#include "eval/truth_eval.h"
#include "eval/truth_report.h"
#include "keygraph/param_text.h"

namespace kg::cli {

Options truth_options(TruthEvalOptions& o, std::string& out_dir, bool& quiet) {
  std::string methods;
  for (const std::string& m : o.methods) methods += (methods.empty() ? "" : ",") + m;
  Options options(
      "eval",
      "--truth MANIFEST (--models DIR|M.json | --index I.kgi) [--methods M,...|all]\n"
      "       [--tolerance PX] [--set NAME=VALUE]... [--threads N] [-o DIR] [--gallery]\n"
      "       [-q]",
      "Detectors scored against hand-marked ground truth (docs/EVAL.md): found, false\n"
      "detections, by size, time. Every input is checked before the first detection.");
  options.text("--truth", "MANIFEST", o.manifest, "the ground-truth manifest (.jsonl; required)")
      .text("--models", "DIR|M.json", o.models,
            "model images: a directory (each image a model) or a models.json")
      .text("--index", "I.kgi", o.index, "or a built index (keygraph methods only)")
      .value("--methods", "M,...|all",
             "keygraph, keygraph-mser and/or baselines (sift-magsac, ...); all: every one\n"
             "(with --index: keygraph)",
             method_list_option(o.methods, &o.methods_set), methods)
      .number("--tolerance", "PX", o.tolerance, 0, 1e6, true,
              "a detection is correct when every corner is within PX pixels");
  declare_eval_settings(
      options, o.params, o.detector, &o.params_set,
      "a parameter of keygraph/params.h (with --models), or a runtime option\n"
      "of the keygraph methods' detectors: min_confidence, time_budget_ms,\n"
      "search_arcs_per_leaf, ransac_barren_draws, align_min_ncc,\n"
      "align_coarse_min_ncc, upsampled_min_confidence, upsampled_scene_keypoints");
  options
      .text("-o, --out, --output", "DIR", out_dir,
            "also write the report (tables, pictures) into DIR")
      .flag("--gallery", o.gallery,
            "with --out: draw the scenes with a miss or a false detection (replacing an\n"
            "earlier run's gallery)")
      .flag("-q, --quiet", quiet,
            "no progress on stderr (by default one line rewritten in place on a\n"
            "terminal, otherwise a line every 10 %)")
      .example("keygraph eval --truth exit.jsonl --models exit-sign-models.json --out report/");
  return options;
}

int cmd_eval_truth(const Args& args) {
  TruthEvalOptions options;
  std::string out_dir;
  bool quiet = false;
  const Options table = truth_options(options, out_dir, quiet);
  if (const int exit_code = table.parse(args); exit_code >= 0) return exit_code;
  if (options.manifest.empty()) return table.usage_error("--truth needs a manifest");
  if (options.gallery && out_dir.empty())
    return table.usage_error("--gallery draws into the report: give --out DIR");
  // Parameters out of range (--set) are the command line's fault.
  if (Status s = format::validate_params(options.params); !s) return table.usage_error(s.message());
  TruthResults results;
  ProgressReporter progress({"eval", "case", is_terminal(stderr), false}, quiet ? nullptr : stderr);
  // Every output path once the inputs are known, before any model is built.
  const auto check_outputs = [&](const TruthResults& known) {
    return out_dir.empty() ? Status::ok() : check_truth_report(out_dir, options, known);
  };
  Status s = evaluate_truth(options, results, progress.callback(), check_outputs);
  progress.finish();
  if (!s) return fail("eval: " + s.message());
  std::fputs(truth_text(truth_tallies(results), options, results).c_str(), stdout);
  if (!out_dir.empty()) {
    if (s = write_truth_report(out_dir, options, results); !s) return fail("eval: " + s.message());
  }
  return 0;
}

}  // namespace kg::cli
