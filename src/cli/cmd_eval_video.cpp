// keygraph eval --video: its options are the Options table below (keygraph eval --help).
//
// A video with ground truth per frame (eval/video_manifest.h, docs/EVAL.md)
// processed in order, by the tracker and by detection alone in the same run
// (eval/video_eval.h): the scores of both on stdout.
#include <cstdio>

#include "builder/progress.h"
#include "cli/commands.h"
#include "cli/device/options.h"
#include "core/index/index_format.h"
#include "eval/video_eval.h"

namespace kg::cli {

Options video_options(VideoEvalOptions& o, bool& json, bool& quiet) {
  Options options(
      "eval",
      "--video MANIFEST (--models DIR|M.json | --index I.kgi) [--tolerance PX]\n"
      "       [--detect-interval N] [--set NAME=VALUE]... [--threads N] [--json] [-q]",
      "A video with ground truth per frame (keygraph synth --video writes one), processed\n"
      "in order with tracking and by detection alone: frames found, corner jitter, id\n"
      "switches, wrong detections, frames until a lost object is dropped, time.");
  options
      .text("--video", "MANIFEST", o.manifest,
            "the ground truth: eval --truth's manifest, one line per frame in order; a\n"
            "line without \"instances\" is a frame without ground truth (required)")
      .text("--models", "DIR|M.json", o.models,
            "model images: a directory (each image a model) or a models.json")
      .text("--index", "I.kgi", o.index, "or a built index")
      .number("--tolerance", "PX", o.tolerance, 0, 1e6, false,
              "an object is found when every corner is within PX pixels (0: 10, or 15\n"
              "for frames wider than 960)")
      .integer("--detect-interval", "N", o.tracker.detect_interval, 1, 1000000,
               "the tracker's full detection every N frames while objects are followed");
  declare_eval_settings(options, o.params, o.detector, &o.params_set,
                        "a parameter of keygraph/params.h (with --models), or a runtime option\n"
                        "of the detectors: min_confidence, time_budget_ms, search_arcs_per_leaf,\n"
                        "ransac_barren_draws, align_min_ncc, align_coarse_min_ncc,\n"
                        "upsampled_min_confidence, upsampled_scene_keypoints");
  options.flag("--json", json, "the scores as one JSON object instead of the table")
      .flag("-q, --quiet", quiet,
            "no progress on stderr (by default one line rewritten in place on a\n"
            "terminal, otherwise a line every 10 %)")
      .example("keygraph synth --video -o seq1 --seed 1")
      .example("keygraph eval --video seq1/video.jsonl --models seq1/signs");
  return options;
}

int cmd_eval_video(const Args& args) {
  VideoEvalOptions options;
  bool json = false, quiet = false;
  const Options table = video_options(options, json, quiet);
  if (const int exit_code = table.parse(args); exit_code >= 0) return exit_code;
  if (options.manifest.empty()) return table.usage_error("--video needs a manifest");
  if (options.models.empty() == options.index.empty())
    return table.usage_error("give one of --models DIR|M.json and --index I.kgi");
  if (Status s = format::validate_params(options.params); !s) return table.usage_error(s.message());
  VideoResults results;
  ProgressReporter progress({"eval", "frame", is_terminal(stderr), false},
                            quiet ? nullptr : stderr);
  const Status s = evaluate_video(options, results, progress.callback());
  progress.finish();
  if (!s) return fail("eval: " + s.message());
  std::fputs((json ? video_json(results) : video_text(results)).c_str(), stdout);
  return 0;
}

}  // namespace kg::cli
