// keygraph eval --truth: its options are the Options table below (keygraph eval --help).
//
// Detectors scored against a ground-truth manifest (docs/EVAL.md): the
// table on stdout, the files of eval/truth_report.h in --out. Every input
// is checked before the first detection, and nothing is written unless the
// whole run succeeds.
#include <cstdio>
#include <filesystem>

#include "builder/progress.h"
#include "cli/commands.h"
#include "cli/device/options.h"
#include "core/index/index_format.h"
#include "eval/baselines.h"
#include "eval/truth_eval.h"
#include "eval/truth_report.h"
#include "keygraph/param_text.h"

namespace kg::cli {

namespace {}  // namespace

Options truth_options(TruthEvalOptions& o, std::string& out_dir, bool& quiet) {
  std::string methods;
  for (const std::string& m : o.methods) methods += (methods.empty() ? "" : ",") + m;
  Options options("eval",
                  "--truth MANIFEST (--models DIR|M.json | --index I.kgi) [--methods M,...|all]\n"
                  "       [--tolerance PX] [--set NAME=VALUE]... [-o DIR] [--gallery] [-q]",
                  "Detectors scored against hand-marked ground truth (docs/EVAL.md): found, false\n"
                  "detections, by size, time. Every input is checked before the first detection.");
  options.text("--truth", "MANIFEST", o.manifest, "the ground-truth manifest (.jsonl; required)")
      .text("--models", "DIR|M.json", o.models,
            "model images: a directory (each image a model) or a models.json")
      .text("--index", "I.kgi", o.index, "or a built index (keygraph methods only)")
      .value(
          "--methods", "M,...|all",
          "keygraph, keygraph-mser and/or baselines (sift-magsac, ...); all: every one",
          [&o](const std::string& v) {
            o.methods = method_list(v);
            return o.methods.empty() ? std::string("--methods is empty") : std::string();
          },
          methods)
      .number("--tolerance", "PX", o.tolerance, 0, 1e6, true,
              "a detection is correct when every corner is within PX pixels")
      .value("--set", "NAME=VALUE", "a parameter of keygraph/params.h (with --models)",
             [&o](const std::string& v) {
               const Status s = set_param(o.params, v);
               o.params_set = true;
               return s ? std::string() : s.message();
             })
      .repeatable()
      .text("-o, --out, --output", "DIR", out_dir,
            "also write the report (tables, pictures) into DIR")
      .flag("--gallery", o.gallery, "with --out: draw the scenes with a miss or a false detection")
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
  if (Status s = format::validate_params(options.params); !s) return fail("eval: " + s.message());
  if (!out_dir.empty()) {
    // A bad output directory fails now, not after the run.
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path out(out_dir);
    const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
    if (fs::exists(out, ec) ? !fs::is_directory(out, ec) : !fs::is_directory(parent, ec))
      return fail("eval: --out " + out_dir + ": not a directory (nor one that can be created)");
  }
  TruthResults results;
  ProgressReporter progress({"eval", "case", is_terminal(stderr), false}, quiet ? nullptr : stderr);
  Status s = evaluate_truth(options, results, progress.callback());
  progress.finish();
  if (!s) return fail("eval: " + s.message());
  std::fputs(truth_text(truth_tallies(results), options, results).c_str(), stdout);
  if (!out_dir.empty()) {
    if (s = write_truth_report(out_dir, options, results); !s) return fail("eval: " + s.message());
  }
  return 0;
}

}  // namespace kg::cli
