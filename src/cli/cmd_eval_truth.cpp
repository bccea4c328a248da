// keygraph eval --truth MANIFEST (--models DIR|models.json | --index I.kgi)
//               [--methods M,...|all] [--tolerance PX] [--set NAME=VALUE]...
//               [--out DIR] [--gallery]
//
// Detectors scored against a ground-truth manifest (docs/EVAL.md): the
// table on stdout, the files of build/truth_report.h in --out. Every input
// is checked before the first detection, and nothing is written unless the
// whole run succeeds.
#include <cstdio>
#include <filesystem>

#include "build/baselines.h"
#include "build/param_overrides.h"
#include "build/truth_eval.h"
#include "build/truth_report.h"
#include "cli/commands.h"
#include "core/index_format.h"

namespace kg::cli {

namespace {

bool progress_shown = false;

void print_progress(const std::string& method, int scene, int scenes) {
  progress_shown = true;
  std::fprintf(stderr, "\r%-13s scene %4d/%-4d", method.c_str(), scene + 1, scenes);
}

void clear_progress() {
  if (progress_shown) std::fprintf(stderr, "\r%60s\r", "");
  progress_shown = false;
}

}  // namespace

int cmd_eval_truth(const Args& args) {
  TruthEvalOptions options;
  std::string out_dir;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--gallery") {
      options.gallery = true;
      continue;
    }
    if (i + 1 >= args.size()) return fail("eval: " + a + " needs a value (or is unknown)");
    const std::string& v = args[++i];
    if (a == "--truth") {
      options.manifest = v;
    } else if (a == "--models") {
      options.models = v;
    } else if (a == "--index") {
      options.index = v;
    } else if (a == "--methods") {
      options.methods = method_list(v);
    } else if (a == "--tolerance") {
      char* end = nullptr;
      options.tolerance = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !(options.tolerance > 0) || options.tolerance > 1e6)
        return fail("eval: --tolerance takes a positive number of pixels, got '" + v + "'");
    } else if (a == "--set") {
      if (Status s = apply_param_override(v, options.params); !s)
        return fail("eval: " + s.message());
      options.params_set = true;
    } else if (a == "--out") {
      out_dir = v;
    } else {
      return fail("eval: unknown option " + a + " (with --truth)");
    }
  }
  if (options.manifest.empty()) return fail("eval: --truth needs a manifest");
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
  Status s = evaluate_truth(options, results, print_progress);
  clear_progress();
  if (!s) return fail("eval: " + s.message());
  std::fputs(truth_text(truth_tallies(results), options, results).c_str(), stdout);
  if (!out_dir.empty()) {
    if (s = write_truth_report(out_dir, options, results); !s) return fail("eval: " + s.message());
  }
  return 0;
}

}  // namespace kg::cli
