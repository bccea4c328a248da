// The keygraph subcommands that need no OpenCV: built into the desktop
// keygraph and into the device build (KG_BUILD_DEVICE_CLI). Each returns the
// process exit code and reports any failure as one line on stderr.
#pragma once

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
// The options of both detects; `draw_format`: the picture format --draw writes.
Options detect_options(std::string& index_path, std::string& draw, bool& json,
                       std::vector<std::string>& scenes, DetectSettings& settings,
                       const std::string& draw_format);

}  // namespace kg::cli
