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
#include "eval/synth/synth_video.h"

namespace kg::cli {

namespace {

bool given(const Args& args, const std::string& name) {
  for (const std::string& a : args) {
    if (a == name || a.rfind(name + "=", 0) == 0) return true;
  }
  return false;
}

int synth_video(const Args& args, const Options& table, const SynthSetOptions& set,
                const std::string& size, double exposure, bool quiet) {
  if (given(args, "--sign-free"))
    return table.usage_error("--sign-free is for stills, not --video");
  SynthVideoOptions options;
  options.directory = set.directory;
  options.backgrounds = set.backgrounds;
  options.seed = set.seed;
  options.frames = set.frames;
  options.signs = given(args, "--signs") ? set.signs : 10;
  options.exposure = exposure;
  const std::size_t x = size.find('x');
  if (x == std::string::npos || !parse_int(size.substr(0, x), 320, 4096, options.width) ||
      !parse_int(size.substr(x + 1), 240, 4096, options.height))
    return table.usage_error("--size " + size + ": not WxH within 320x240 .. 4096x4096");
  if (options.frames < 30) return table.usage_error("--video needs --frames 30 or more");
  ProgressReporter progress({"synth", "frame", is_terminal(stderr), false},
                            quiet ? nullptr : stderr);
  const Status s = write_synth_video(options, progress.callback());
  progress.finish();
  if (!s) return fail("synth: " + s.message());
  std::printf("%s: a video of %s at %dx%d, %s as models, seed %llu\n", options.directory.c_str(),
              counted(options.frames, "frame").c_str(), options.width, options.height,
              counted(options.signs, "sign").c_str(),
              static_cast<unsigned long long>(options.seed));
  return 0;
}

}  // namespace

int cmd_synth(const Args& args) {
  SynthSetOptions options;
  options.backgrounds = KG_OPENCV_DATA_DIR;
  bool quiet = false, video = false;
  std::string size;  // the frame size, WxH: for --range and --video
  double exposure = 0.5;
  Options table("synth",
                "-o DIR [--seed N] [--signs N] [--frames N] [--sign-free F]\n"
                "       [--range [--size WxH]] [--jpeg Q] [--backgrounds DIR] [-q]\n"
                "       --video -o DIR [--seed N] [--signs N] [--frames N] [--size WxH]\n"
                "       [--exposure F] [-q]",
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
            "and rendered at --size; the distance is in the manifest")
      .integer("--jpeg", "Q", options.frame.jpeg_quality, 0, 100,
               "every frame through JPEG at quality Q (0: none, the default)")
      .text("--backgrounds", "DIR", options.backgrounds, "opencv-doc's photos (the backgrounds)")
      .flag("--video", video,
            "a video instead (src/eval/synth/synth_video.h): one of the first N signs\n"
            "(default 10) filmed at 30 fps along a hand-held path (approach, fast pans,\n"
            "occlusion, leaving and coming back, turns) with motion blur; ground truth\n"
            "per frame in DIR/video.jsonl for keygraph eval --video")
      .text("--size", "WxH", size,
            "the frame size (640x480 by default): with --range the frame of the same\n"
            "camera (4:3 to 16:9; 1280x720: the same scenes, every sign twice as long);\n"
            "with --video any size from 320x240 to 4096x4096")
      .number("--exposure", "F", exposure, 0, 1, false,
              "with --video: the shutter's open share of the frame interval (the motion\n"
              "blur)")
      .flag("-q, --quiet", quiet,
            "no progress on stderr (by default one line rewritten in place on a\n"
            "terminal, otherwise a line every 10 %)")
      .example("keygraph synth -o signs-bench --frames 100")
      .example("keygraph synth -o small-720 --range --size 1280x720 --seed 3")
      .example("keygraph synth --video -o seq1 --seed 1");
  if (const int exit_code = table.parse(args); exit_code >= 0) return exit_code;
  if (options.directory.empty()) return table.usage_error("no output directory given (-o DIR)");
  if (video) {
    if (options.range || given(args, "--jpeg"))
      return table.usage_error("--range and --jpeg are for stills, not --video");
    return synth_video(args, table, options, size.empty() ? "640x480" : size, exposure, quiet);
  }
  if (given(args, "--exposure")) return table.usage_error("--exposure is for --video");
  int width = 640, height = 480;
  if (!size.empty()) {
    char x = 0, rest = 0;
    if (!options.range) return table.usage_error("--size is for --range and --video");
    if (std::sscanf(size.c_str(), "%d%c%d%c", &width, &x, &height, &rest) != 3 || x != 'x' ||
        !valid_range_frame_size(width, height))
      return table.usage_error("--size " + size +
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
