// The keygraph subcommands that need no OpenCV: built into the desktop
// keygraph and into the device build (KG_BUILD_DEVICE_CLI). Each returns the
// process exit code and reports any failure as one line on stderr.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "cli/device/command_line.h"
#include "cli/device/detect_settings.h"
#include "cli/device/options.h"

namespace kg::cli {

// keygraph inspect I.kgi
int cmd_inspect(const Args& args);
// keygraph live --index I.kgi (--v4l2 DEV | --libcamera [ID] | --images DIR) ...
int cmd_live(const Args& args);
// keygraph bench --index I.kgi [--repeat N] FRAME...
int cmd_bench(const Args& args);
// keygraph detect on image files read by platform/files (PGM; other formats
// when that library has OpenCV): the device build's `detect`.
int cmd_detect_files(const Args& args);
// The command line both detects share (the desktop one and cmd_detect_files):
// its options, and parse(), which checks it whole before the first scene is
// read. Not copyable: the options write into its fields.
struct DetectCommand {
  std::string index_path, draw;
  bool json = false;
  std::vector<std::string> scenes;  // the scene files, directories expanded
  std::vector<std::string> inputs;  // the scenes and the index: no output may be one
  std::vector<std::string> drawn;   // with --draw: scene i's picture
  DetectSettings settings;

  // `draw_format`: the picture format --draw writes, for the help.
  explicit DetectCommand(const std::string& draw_format);
  DetectCommand(const DetectCommand&) = delete;
  DetectCommand& operator=(const DetectCommand&) = delete;

  // Parses `args`, expands the scenes and plans every --draw picture
  // (draw_targets.h: `draw_ext` for pictures in a directory, `writable(path)`
  // whether this build writes such a file, `unwritable_hint` added to the
  // error for a name it does not). Returns the exit code to stop with, or -1.
  int parse(const Args& args, const std::string& draw_ext,
            const std::function<bool(const std::string&)>& writable,
            const std::string& unwritable_hint);
  int usage_error(const std::string& message) const { return options_.usage_error(message); }

 private:
  std::vector<std::string> scene_args_;
  Options options_;
};

}  // namespace kg::cli
