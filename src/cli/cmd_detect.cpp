// keygraph detect: its options are the Options table below (keygraph detect --help).
#include <chrono>
#include <cstdio>

#include "builder/desktop_detect.h"
#include "builder/image_io.h"
#include "cli/commands.h"
#include "cli/device/device_commands.h"
#include "cli/device/json.h"

namespace kg::cli {

int cmd_detect(const Args& args) {
  std::string index_path, draw;
  bool json = false;
  std::vector<std::string> scenes;
  const Options options = detect_options(index_path, draw, json, scenes, "any image format");
  if (const int exit_code = options.parse(args); exit_code >= 0) return exit_code;
  if (index_path.empty()) return options.usage_error("no index given (--index I.kgi)");
  if (scenes.empty()) return options.usage_error("no scene images given");
  std::vector<std::string> drawn;
  if (!draw.empty()) {
    if (std::string error = draw_paths(draw, scenes, drawn); !error.empty())
      return fail("detect: " + error);
  }
  // The index is read into memory (not mapped): a file changed in place
  // meanwhile cannot crash the process (model_index.h).
  ModelIndex index;
  Status s = ModelIndex::read(index_path, index);
  if (!s) return fail(s.message());
  std::vector<std::string> inputs = scenes;
  inputs.push_back(index_path);
  DesktopDetector detector(index);
  int exit_code = 0;
  DetectionList found;
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    const std::string& scene = scenes[i];
    cv::Mat gray;
    s = load_image(scene, gray);
    if (!s) {
      exit_code = fail(s.message());
      continue;
    }
    const auto start = std::chrono::steady_clock::now();
    s = detector.detect(gray, found);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (!s) {
      exit_code = fail(scene + ": " + s.message());
      continue;
    }
    if (json) {
      std::printf("%s\n",
                  detection_json(scene, gray.cols, gray.rows, ms, found, detector.stats()).c_str());
    } else {
      std::printf("%s: %zu detection(s) in %.1f ms\n", scene.c_str(), found.size(), ms);
      for (const Detection& d : found) {
        std::printf("  %.*s: inliers %d, score %.3f, appearance %.2f, confidence %.2f, corners",
                    static_cast<int>(d.model_name.size()), d.model_name.data(), d.inliers, d.score,
                    d.appearance, d.confidence);
        for (const Point2f& c : d.corners) std::printf(" (%.1f, %.1f)", c.x, c.y);
        std::printf("\n");
      }
    }
    std::fflush(stdout);
    if (!draw.empty()) {
      std::string error;
      if (!write_image_atomically(drawn[i], draw_detections(gray, found), inputs, error))
        exit_code = fail("detect: --draw " + error);
    }
  }
  return exit_code;
}

}  // namespace kg::cli
