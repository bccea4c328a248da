// keygraph: build model indexes and detect models in images.
//
// One main for both builds of the tool (src/cli/CMakeLists.txt): the
// desktop keygraph (KG_CLI_DESKTOP, with OpenCV) has every command; the
// device keygraph has the commands of cli/device/ only.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "cli/device/device_commands.h"
#include "cli/device/options.h"
#include "core/index/index_format.h"
#include "keygraph/detector.h"
#include "platform/files/image_limits.h"
#if KG_CLI_DESKTOP
#include "cli/commands.h"
#endif

namespace {

using kg::Limits;
namespace platform = kg::platform;

struct Command {
  const char* name;
  const char* summary;
  int (*run)(const kg::cli::Args& args);  // null: not in this build
};

// Every command, in the order `keygraph help` lists them. Each command's
// options and help are in its own file (its Options table).
constexpr Command kCommands[] = {
#if KG_CLI_DESKTOP
    {"build", "compile model images into one index (.kgi) and rate each model", kg::cli::cmd_build},
    {"detect", "find the index's models in scene images", kg::cli::cmd_detect},
    {"demo", "build box.png from opencv-doc and find it in box_in_scene.png", kg::cli::cmd_demo},
    {"eval", "evaluate detectors: Oxford crops, the sign benchmark, or ground truth",
     kg::cli::cmd_eval},
    {"manifest", "a ground-truth manifest for a real photo set", kg::cli::cmd_manifest},
    {"synth", "generate the labelled indoor-sign benchmark", kg::cli::cmd_synth},
    {"repeatability", "keypoint repeatability, density and time (Oxford layout)",
     kg::cli::cmd_repeatability},
#else
    {"detect", "find the index's models in PGM images", kg::cli::cmd_detect_files},
    {"build", "(desktop keygraph only)", nullptr},
    {"demo", "(desktop keygraph only)", nullptr},
    {"eval", "(desktop keygraph only)", nullptr},
    {"manifest", "(desktop keygraph only)", nullptr},
    {"synth", "(desktop keygraph only)", nullptr},
    {"repeatability", "(desktop keygraph only)", nullptr},
#endif
    {"live", "follow the models through camera frames or image files", kg::cli::cmd_live},
    {"bench", "time detect() per stage on frames in memory", kg::cli::cmd_bench},
    {"inspect", "an index's header, parameters, sections and models", kg::cli::cmd_inspect},
};

void usage(std::FILE* out) {
  std::fprintf(out,
               "usage: keygraph COMMAND [options]\n"
               "       keygraph help COMMAND    (or keygraph COMMAND --help): its options\n"
               "       keygraph --version       the version and the index formats it reads\n"
               "\n"
               "commands:\n");
  for (const Command& c : kCommands) std::fprintf(out, "  %-15s %s\n", c.name, c.summary);
  std::fprintf(out,
               "  %-15s %s\n"
               "\n"
               "Image files must be regular files of at most %lld pixels (width x height,\n"
               "checked on the size the file declares, before decoding) and %d pixels a\n"
               "side for detection; live and bench skip larger frames with a warning.\n"
               "Outputs (-o, --draw) are written whole or not at all and replace regular\n"
               "files only, never an input; they are checked before the work starts.\n"
               "-o (also --out, --output) names what a command writes: a file when it\n"
               "writes one (build, manifest), a directory when it writes several (demo,\n"
               "eval, synth). --draw DIR writes one picture per input into DIR.\n"
               "An option that takes a value is given once unless its help says\n"
               "repeatable; -- ends the options. -q (--quiet): no progress on stderr.\n"
               "Exit codes: 0 done, 1 failed, 2 usage error.\n"
               "\n"
               "example:\n"
               "  keygraph demo --out /tmp\n",
               "help", "this text", platform::kMaxImagePixels, Limits::kMaxSide);
}

const Command* find_command(const std::string& name) {
  for (const Command& c : kCommands) {
    if (name == c.name) return &c;
  }
  return nullptr;
}

int unknown_command(const std::string& name) {
  std::fprintf(stderr, "keygraph: unknown command '%s' (see keygraph --help)\n", name.c_str());
  return kg::cli::kUsageError;
}

// keygraph --version: the library's version, the build, and the index
// formats this keygraph reads (and, on the desktop, writes).
int version() {
  using kg::format::kVersionMajor;
  using kg::format::kVersionMinor;
#if KG_CLI_DESKTOP
  std::printf("keygraph %s (desktop build, OpenCV %s)\n", KG_VERSION, CV_VERSION);
  std::printf(
      "index format: writes %u.%u; reads %u.0 to %u.%u (and later %u.x files, without what "
      "they add)\n",
      kVersionMajor, kVersionMinor, kVersionMajor, kVersionMajor, kVersionMinor, kVersionMajor);
#else
  std::printf("keygraph %s (device build, no OpenCV)\n", KG_VERSION);
  std::printf("index format: reads %u.0 to %u.%u (and later %u.x files, without what they add)\n",
              kVersionMajor, kVersionMajor, kVersionMinor, kVersionMajor);
#endif
  return 0;
}

int run_command(const Command& c, const kg::cli::Args& args) {
  kg::cli::set_command_name(c.name);
  if (c.run == nullptr) {
    return kg::cli::fail(std::string(c.name) +
                         ": not in this build of keygraph (a device build, without "
                         "OpenCV); use the desktop keygraph");
  }
  return c.run(args);
}

int run(int argc, char** argv) {
  if (argc < 2) {
    usage(stderr);
    return kg::cli::kUsageError;
  }
  const std::string command = argv[1];
  if (command == "--version") return version();
  if (command == "help" || command == "--help" || command == "-h") {
    if (argc < 3) {
      usage(stdout);
      return 0;
    }
    const Command* c = find_command(argv[2]);
    return c != nullptr ? run_command(*c, {"--help"}) : unknown_command(argv[2]);
  }
  const Command* c = find_command(command);
  return c != nullptr ? run_command(*c, kg::cli::Args(argv + 2, argv + argc))
                      : unknown_command(command);
}

}  // namespace

int main(int argc, char** argv) {
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
