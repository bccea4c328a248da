// keygraph detect: its options are the Options table of detect_options()
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
  std::string index_path, draw;
  bool json = false;
  std::vector<std::string> scene_args, scenes;
  DetectSettings settings;
  const Options options =
      detect_options(index_path, draw, json, scene_args, settings, "PNG, in colour");
  if (const int exit_code = options.parse(args); exit_code >= 0) return exit_code;
  if (index_path.empty()) return options.usage_error("no index given (--index I.kgi)");
  if (scene_args.empty()) return options.usage_error("no scene images given");
  if (std::string error = expand_scene_paths(scene_args, scenes); !error.empty())
    return fail(error);
  std::vector<std::string> inputs = scenes;
  inputs.push_back(index_path);
  // Every picture is checked before the first scene (draw_targets.h).
  std::vector<std::string> drawn;
  if (!draw.empty()) {
    const auto writable = [](const std::string& path) { return cv::haveImageWriter(path); };
    if (std::string error = plan_drawings(draw, scenes, ".png", writable, inputs, drawn);
        !error.empty())
      return fail(error);
  }
  // The index is read into memory (not mapped): a file changed in place
  // meanwhile cannot crash the process (model_index.h).
  ModelIndex index;
  Status s = ModelIndex::read(index_path, index);
  if (!s) return fail(s.message());
  DetectOptions runtime;
  if (s = settings.options_for(index, runtime); !s) return options.usage_error(s.message());
  DesktopDetector detector(index, settings.limits());
  if (s = detector.core().set_options(runtime); !s) return fail(s.message());
  int exit_code = 0;
  DetectionList found;
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    const std::string& scene = scenes[i];
    cv::Mat gray;
    s = load_image(scene, gray);
    if (!s) {
      exit_code = scene_failed(scene, s.message(), json);
      continue;
    }
    const auto start = std::chrono::steady_clock::now();
    s = detector.detect(gray, found);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (!s) {
      exit_code = scene_failed(scene, scene + ": " + s.message(), json);
      continue;
    }
    print_detections(scene, view_of(gray), ms, found, detector.stats(), json);
    std::fflush(stdout);
    if (!draw.empty()) {
      // The picture in the scene's colours (gray when they cannot be read).
      cv::Mat picture;
      if (!load_color(scene, picture) || picture.size() != gray.size()) picture = gray;
      std::string error;
      if (!write_image_atomically(drawn[i], draw_scene(picture, found), inputs, error))
        exit_code = fail("--draw " + error);
    }
  }
  return exit_code;
}

}  // namespace kg::cli
