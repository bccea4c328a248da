// keygraph synth: its options are the Options table below (keygraph synth --help).
// Writes the synthetic indoor-sign benchmark (src/eval/synth/synth_set.h): signs
// drawn by the project, composited into opencv-doc photos with their
// ground truth in DIR/manifest.txt.
#include <cstdio>
#include <string>

#include "builder/progress.h"
#include "cli/commands.h"
#include "cli/device/options.h"
#include "eval/synth/sign_catalogue.h"
#include "eval/synth/synth_set.h"

namespace kg::cli {

int cmd_synth(const Args& args) {
  SynthSetOptions options;
  options.backgrounds = KG_OPENCV_DATA_DIR;
  bool quiet = false;
  Options table(
      "synth",
      "-o DIR [--seed N] [--signs N] [--frames N] [--sign-free F]\n       [--backgrounds DIR] [-q]",
      "Generates the labelled indoor-sign benchmark: signs drawn by the project,\n"
      "composited into opencv-doc photos, ground truth in DIR/manifest.txt.");
  table
      .text("-o, --out, --output", "DIR", options.directory,
            "the directory to create (required; new or empty)")
      .unsigned64("--seed", "N", options.seed, "seed of the signs' style and of the frames")
      .integer("--signs", "N", options.signs, 1, sign_catalogue_size(),
               "the first N signs of the catalogue")
      .integer("--frames", "N", options.frames, 1, 100000, "frames (640x480) to render")
      .number("--sign-free", "F", options.sign_free_fraction, 0, 1, false,
              "fraction of the frames without a sign")
      .text("--backgrounds", "DIR", options.backgrounds, "opencv-doc's photos (the backgrounds)")
      .flag("-q, --quiet", quiet,
            "no progress on stderr (by default one line rewritten in place on a\n"
            "terminal, otherwise a line every 10 %)")
      .example("keygraph synth -o signs-bench --frames 100");
  if (const int exit_code = table.parse(args); exit_code >= 0) return exit_code;
  if (options.directory.empty()) return table.usage_error("no output directory given (-o DIR)");
  ProgressReporter progress({"synth", "frame", is_terminal(stderr), false},
                            quiet ? nullptr : stderr);
  const Status s = write_synth_set(options, progress.callback());
  progress.finish();
  if (!s) return fail("synth: " + s.message());
  std::printf("%s: %s, %s (%d sign-free), seed %llu\n", options.directory.c_str(),
              counted(options.signs, "sign").c_str(), counted(options.frames, "frame").c_str(),
              static_cast<int>(options.frames * options.sign_free_fraction + 0.5),
              static_cast<unsigned long long>(options.seed));
  return 0;
}

}  // namespace kg::cli
