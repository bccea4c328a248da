// keygraph: build model indexes and detect models in images.
//
// One main for both builds of the tool (src/cli/CMakeLists.txt): the
// desktop keygraph (KG_CLI_DESKTOP, with OpenCV) has every command; the
// device keygraph has the commands of cli/device/ only.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "cli/device/device_commands.h"
#include "keygraph/detector.h"
#include "platform/files/file_source.h"
#include "platform/files/image_limits.h"
#if KG_CLI_DESKTOP
#include "cli/commands.h"
#endif

namespace {

using kg::Limits;
namespace platform = kg::platform;

void usage(std::FILE* out) {
  std::fprintf(out,
               "usage: keygraph <command> [options]\n"
               "\n"
               "commands:\n");
#if KG_CLI_DESKTOP
  std::fprintf(
      out,
      "  build [--name NAME]... [--roi X,Y,W,H] [--detector hessian|mser]\n"
      "        [--structure 2|3|4] [--vertex-descriptor none|sift]\n"
      "        [--encoding float32|int16|int8] [--draw-model DIR] [--no-look-alikes]\n"
      "        MODEL.png... -o OUT.kgi     compile model images into one index, rate them\n"
      "  detect --index I.kgi [--json] [--draw OUT.png] SCENE...\n"
      "                                    find the index's models in scene images\n"
      "  demo [--out DIR]                  build box.png from opencv-doc and find it\n"
      "                                    in box_in_scene.png\n"
      "  eval --dataset DIR [--subsets a,b] [--crops N] [--size S] [--centre]\n"
      "       [--seed N] [--set NAME=VALUE]... [--methods M,...|all] [--negatives]\n"
      "       [--curves] [--out DIR] [--csv FILE]\n"
      "                                    crops of img1 found in img2..6 (Oxford layout);\n"
      "                                    --curves: precision-recall and RANSAC iterations\n"
      "  eval --synth DIR [--sizes 1,10,50] [--methods M,...|all] [--set ...] [--out DIR]\n"
      "                                    the sign benchmark of keygraph synth\n"
      "  eval --truth MANIFEST (--models DIR|M.json | --index I.kgi) [--methods M,...|all]\n"
      "       [--tolerance PX] [--set NAME=VALUE]... [--out DIR] [--gallery]\n"
      "                                    detectors against hand-marked ground truth\n"
      "                                    (docs/EVAL.md): found, false, by size, time\n"
      "  manifest exit-signs|planar-pairs|negatives DIR -o OUT.jsonl\n"
      "       [--split dev|test|model-bursts]\n"
      "                                    a ground-truth manifest for a real photo set\n"
      "  synth -o DIR [--seed N] [--signs N] [--frames N] [--sign-free F]\n"
      "                                    generate a labelled indoor-sign benchmark\n"
      "  repeatability --dataset DIR [--subsets a,b] [--detectors D,...]\n"
      "       [--set NAME=VALUE]... [--max-keypoints N] [--tolerance PX] [--csv FILE]\n"
      "                                    keypoint repeatability img1 -> img2..6 (Oxford\n"
      "                                    layout), density, keygraph triangles, time;\n"
      "                                    D: hessian|mser[:NAME=VALUE...], sift, orb, akaze\n");
#else
  std::fprintf(out,
               "  detect --index I.kgi [--json] [--draw OUT.pgm] SCENE.pgm...\n"
               "                                    find the index's models in PGM images\n");
#endif
  std::fprintf(out,
               "  live --index I.kgi (--v4l2 /dev/videoN | --libcamera [ID] | --images PATH)\n"
               "       [--size WxH] [--loop] [--json] [--draw DIR] [--frames N]\n"
               "                                    detect on every camera frame or image file;\n"
               "                                    frames per second on stderr; Ctrl-C stops\n"
               "  bench --index I.kgi [--repeat N] [--json] FRAME...\n"
               "                                    time detect() per stage on frames in memory\n"
               "  inspect I.kgi                     header, parameters, sections (checksums\n"
               "                                    verified), models and bytes per arc\n"
               "  help                              this text\n"
               "\n"
               "Image files must be regular files of at most %lld pixels (width x height,\n"
               "checked on the size the file declares, before decoding) and %d pixels a\n"
               "side for detection; live and bench skip larger frames with a warning.\n"
               "Outputs (-o, --draw) are written whole or not at all and replace regular\n"
               "files only, never an input.\n",
               platform::kMaxImagePixels, Limits::kMaxSide);
}

int run(int argc, char** argv) {
  if (argc < 2) {
    usage(stderr);
    return 2;
  }
  const std::string command = argv[1];
  kg::cli::Args args(argv + 2, argv + argc);
#if KG_CLI_DESKTOP
  if (command == "build") return kg::cli::cmd_build(args);
  if (command == "detect") return kg::cli::cmd_detect(args);
  if (command == "demo") return kg::cli::cmd_demo(args);
  if (command == "eval") return kg::cli::cmd_eval(args);
  if (command == "manifest") return kg::cli::cmd_manifest(args);
  if (command == "synth") return kg::cli::cmd_synth(args);
  if (command == "repeatability") return kg::cli::cmd_repeatability(args);
#else
  if (command == "detect") return kg::cli::cmd_detect_files(args);
  if (command == "build" || command == "demo" || command == "eval" || command == "synth" ||
      command == "repeatability" || command == "manifest") {
    return kg::cli::fail(command +
                         ": not in this build of keygraph (a device build, without "
                         "OpenCV); use the desktop keygraph");
  }
#endif
  if (command == "live") return kg::cli::cmd_live(args);
  if (command == "bench") return kg::cli::cmd_bench(args);
  if (command == "inspect") return kg::cli::cmd_inspect(args);
  if (command == "help" || command == "--help" || command == "-h") {
    usage(stdout);
    return 0;
  }
  return kg::cli::fail("unknown command '" + command + "' (see keygraph help)");
}

// OpenCV imgcodecs reads its image size limit from the environment once,
// while its library is loaded (image_limits.h): setting it from main() is
// too late, and so is an ELF pre-initialiser (the C library's start-up
// resets the environment after it). So the first time, keygraph sets the
// variable and executes itself again (same process id, same arguments);
// if that fails it carries on, and images are then size-checked after
// decoding only.
void limit_image_decoders_before_load(char** argv) {
  if (!kg::platform::file_source_uses_opencv()) return;
  const char* before = std::getenv("OPENCV_IO_MAX_IMAGE_PIXELS");
  const std::string previous = before != nullptr ? before : "";
  kg::platform::limit_image_decoders();
  const char* after = std::getenv("OPENCV_IO_MAX_IMAGE_PIXELS");
  if (after != nullptr && previous == after) return;  // already in force
  ::execv("/proc/self/exe", argv);
}

}  // namespace

int main(int argc, char** argv) {
  limit_image_decoders_before_load(argv);
  // Last resort (e.g. std::bad_alloc, cv::Exception): one line and a
  // non-zero exit instead of std::terminate's multi-line abort.
  int exit_code = 0;
  try {
    exit_code = run(argc, argv);
  } catch (const std::exception& e) {
    exit_code = kg::cli::fail(std::string("internal error: ") + e.what());
  }
  // Output that never arrived (a full disk, a closed file) is a failure.
  return kg::cli::check_stdout(exit_code);
}
