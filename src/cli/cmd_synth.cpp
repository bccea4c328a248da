// keygraph synth -o DIR [--seed N] [--signs N] [--frames N] [--sign-free F]
//                [--backgrounds DIR]
// Writes the synthetic indoor-sign benchmark (src/build/synth_set.h): signs
// drawn by the project, composited into opencv-doc photos with their
// ground truth in DIR/manifest.txt.
#include <cstdio>
#include <string>

#include "build/synth_set.h"
#include "cli/commands.h"

namespace kg::cli {

namespace {

bool progress_shown = false;

void print_progress(int done, int total) {
  progress_shown = true;
  std::fprintf(stderr, "\rframe %d/%d", done, total);
}

}  // namespace

int cmd_synth(const Args& args) {
  SynthSetOptions options;
  options.backgrounds = KG_OPENCV_DATA_DIR;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (i + 1 >= args.size()) return fail("synth: " + a + " needs a value (or is unknown)");
    const std::string& v = args[++i];
    try {
      if (a == "-o" || a == "--out") {
        options.directory = v;
      } else if (a == "--seed") {
        options.seed = std::stoull(v);
      } else if (a == "--signs") {
        options.signs = std::stoi(v);
      } else if (a == "--frames") {
        options.frames = std::stoi(v);
      } else if (a == "--sign-free") {
        options.sign_free_fraction = std::stod(v);
      } else if (a == "--backgrounds") {
        options.backgrounds = v;
      } else {
        return fail("synth: unknown option " + a);
      }
    } catch (const std::exception&) {
      return fail("synth: bad number '" + v + "' for " + a);
    }
  }
  if (options.directory.empty()) return fail("synth: no output directory given (-o DIR)");
  const Status s = write_synth_set(options, print_progress);
  if (progress_shown) std::fprintf(stderr, "\r%30s\r", "");
  if (!s) return fail("synth: " + s.message());
  std::printf("%s: %d signs, %d frames (%d sign-free), seed %llu\n", options.directory.c_str(),
              options.signs, options.frames,
              static_cast<int>(options.frames * options.sign_free_fraction + 0.5),
              static_cast<unsigned long long>(options.seed));
  return 0;
}

}  // namespace kg::cli
