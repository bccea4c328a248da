// keygraph detect: its options are the Options table of DetectCommand
// (cli/device/cmd_detect_files.cpp; keygraph detect --help). The desktop
// build's detect: any image format OpenCV reads, the index's own keypoint
// detector (MSER through OpenCV), and pictures in colour.
#include <chrono>
#include <cstdio>

#include <opencv2/imgcodecs.hpp>

#include "builder/desktop_detect.h"
#include "builder/image_io.h"
#include "cli/commands.h"
#include "cli/device/device_commands.h"
#include "cli/device/draw_targets.h"
#include "cli/device/frame_output.h"
#include "cli/device/scene_list.h"

namespace kg::cli {

int cmd_detect(const Args& args) {
  DetectCommand command("PNG, in colour");
  const auto writable = [](const std::string& path) { return cv::haveImageWriter(path); };
  if (const int exit_code = command.parse(args, ".png", writable, ""); exit_code >= 0)
    return exit_code;
  // The index is read into memory (not mapped): a file changed in place
  // meanwhile cannot crash the process (model_index.h).
  ModelIndex index;
  Status s = ModelIndex::read(command.index_path, index);
  if (!s) return fail(s.message());
  DetectOptions runtime;
  if (s = command.settings.options_for(index, runtime); !s) return command.usage_error(s.message());
  DesktopDetector detector(index, command.settings.limits());
  if (s = detector.core().set_options(runtime); !s) return fail(s.message());
  int exit_code = 0;
  DetectionList found;
  for (std::size_t i = 0; i < command.scenes.size(); ++i) {
    const std::string& scene = command.scenes[i];
    cv::Mat gray;
    s = load_image(scene, gray);
    if (!s) {
      exit_code = scene_failed(scene, s.message(), command.json);
      continue;
    }
    const auto start = std::chrono::steady_clock::now();
    s = detector.detect(gray, found);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (!s) {
      exit_code = scene_failed(scene, scene + ": " + s.message(), command.json);
      continue;
    }
    print_detections(scene, view_of(gray), ms, found, detector.stats(), command.json);
    std::fflush(stdout);
    if (!command.draw.empty()) {
      // The picture in the scene's colours (gray when they cannot be read).
      cv::Mat picture;
      if (!load_color(scene, picture) || picture.size() != gray.size()) picture = gray;
      std::string error;
      if (!write_image_atomically(command.drawn[i], draw_scene(picture, found), command.inputs,
                                  error))
        exit_code = fail("--draw " + error);
    }
  }
  return exit_code;
}

}  // namespace kg::cli
