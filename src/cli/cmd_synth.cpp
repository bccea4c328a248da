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
  std::string frame_size;
  Options table("synth",
                "-o DIR [--seed N] [--signs N] [--frames N] [--sign-free F]\n"
                "       [--range [--frame-size WxH]] [--jpeg Q] [--backgrounds DIR] [-q]",
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
      .flag("--range", options.range,
            "the small-sign benchmark (issue 38): signs 20 to 240 px long at 640x480\n"
            "(0.75 to 9 m for a 30 cm sign, log-uniform), drawn in a 640x480 camera\n"
            "and rendered at --frame-size; the distance is in the manifest")
      .text("--frame-size", "WxH", frame_size,
            "with --range: the frame of the same camera (640x480 by default,\n"
            "1280x720: the same scenes, every sign twice as long)")
      .integer("--jpeg", "Q", options.frame.jpeg_quality, 0, 100,
               "every frame through JPEG at quality Q (0: none, the default)")
      .text("--backgrounds", "DIR", options.backgrounds, "opencv-doc's photos (the backgrounds)")
      .flag("-q, --quiet", quiet,
            "no progress on stderr (by default one line rewritten in place on a\n"
            "terminal, otherwise a line every 10 %)")
      .example("keygraph synth -o signs-bench --frames 100")
      .example("keygraph synth -o small-720 --range --frame-size 1280x720 --seed 3");
  if (const int exit_code = table.parse(args); exit_code >= 0) return exit_code;
  if (options.directory.empty()) return table.usage_error("no output directory given (-o DIR)");
  int width = 640, height = 480;
  if (!frame_size.empty()) {
    char x = 0, rest = 0;
    if (!options.range) return table.usage_error("--frame-size needs --range");
    if (std::sscanf(frame_size.c_str(), "%d%c%d%c", &width, &x, &height, &rest) != 3 || x != 'x' ||
        !valid_range_frame_size(width, height))
      return table.usage_error("--frame-size " + frame_size +
                               ": expected WxH of the 640x480 camera, 4:3 to 16:9 (640x480, "
                               "1280x720, 1920x1080)");
  }
  if (options.range) {
    const int jpeg = options.frame.jpeg_quality;
    options.range_frame = range_frame_options(width, height);
    options.range_frame.frame.jpeg_quality = jpeg;
  }
  ProgressReporter progress({"synth", "frame", is_terminal(stderr), false},
                            quiet ? nullptr : stderr);
  const Status s = write_synth_set(options, progress.callback());
  progress.finish();
  if (!s) return fail("synth: " + s.message());
  std::printf("%s: %s, %s (%d sign-free, %dx%d), seed %llu\n", options.directory.c_str(),
              counted(options.signs, "sign").c_str(), counted(options.frames, "frame").c_str(),
              static_cast<int>(options.frames * options.sign_free_fraction + 0.5), width, height,
              static_cast<unsigned long long>(options.seed));
  return 0;
}

}  // namespace kg::cli
