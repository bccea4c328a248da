// keygraph detect: its options are the Options table below (keygraph detect --help).
// The device build's detect: scenes read by platform/files (binary PGM;
// more formats when that library was built with OpenCV), the core detector,
// and the same output as the desktop detect. --draw writes PGM.
#include <chrono>
#include <filesystem>

#include "cli/device/detector_fit.h"
#include "cli/device/device_commands.h"
#include "cli/device/frame_output.h"
#include "cli/device/options.h"
#include "keygraph/detector.h"
#include "platform/files/file_source.h"
#include "platform/files/pgm.h"

namespace kg::cli {

Options detect_options(std::string& index_path, std::string& draw, bool& json,
                       std::vector<std::string>& scenes, const std::string& draw_format) {
  Options options("detect", "--index I.kgi [--json] [--draw OUT] SCENE...",
                  "Finds the index's models in scene images: per scene, the detections with their\n"
                  "inliers, score and corners (scene pixels), and the time.");
  options
      .positional("SCENE...", "scene image files",
                  [&scenes](const std::string& v) {
                    scenes.push_back(v);
                    return std::string();
                  })
      .text("--index", "I.kgi", index_path, "the model index (required)")
      .flag("--json", json, "one JSON object per scene on stdout")
      .text("--draw", "OUT", draw,
            "draw the outlines found into OUT (" + draw_format +
                "); with several scenes,\nOUT_<scene name> next to OUT")
      .example("keygraph detect --index signs.kgi --draw found." +
               std::string(draw_format == "PGM" ? "pgm" : "png") + " scene." +
               std::string(draw_format == "PGM" ? "pgm" : "jpg"));
  return options;
}

int cmd_detect_files(const Args& args) {
  std::string index_path, draw;
  bool json = false;
  std::vector<std::string> scenes;
  Options options = detect_options(index_path, draw, json, scenes, "PGM");
  if (const int exit_code = options.parse(args); exit_code >= 0) return exit_code;
  if (index_path.empty()) return options.usage_error("no index given (--index I.kgi)");
  if (scenes.empty()) return options.usage_error("no scene images given");
  if (!draw.empty() && std::filesystem::path(draw).extension() != ".pgm")
    return fail("detect: --draw " + draw + ": this build writes PGM only (use a .pgm name)");
  std::vector<std::string> drawn;
  if (!draw.empty()) {
    if (std::string error = draw_paths(draw, scenes, drawn); !error.empty())
      return fail("detect: " + error);
  }
  // Read into memory, not mapped: an index changed in place meanwhile
  // cannot crash the process (model_index.h).
  ModelIndex index;
  if (Status s = ModelIndex::read(index_path, index); !s) return fail(s.message());
  std::vector<std::string> inputs = scenes;
  inputs.push_back(index_path);
  if (const std::string problem = core_detector_problem(index); !problem.empty())
    return fail("detect: " + index_path + ": " + problem);

  Detector detector(index);
  DetectionList found;
  platform::GrayImage scene_image, canvas;
  int exit_code = 0;
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    const std::string& scene = scenes[i];
    if (Status s = platform::read_image(scene, scene_image); !s) {
      exit_code = fail(s.message());
      continue;
    }
    const ImageView view = scene_image.view();
    if (const Status fit = fit_detector(detector, view); !fit) {
      exit_code = fail(scene + ": " + fit.message());
      continue;
    }
    const auto start = std::chrono::steady_clock::now();
    const Status s = detector.detect(view, found);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (!s) {
      exit_code = fail(scene + ": " + s.message());
      continue;
    }
    print_detections(scene, view, ms, found, detector.stats(), json);
    std::fflush(stdout);
    if (!draw.empty()) {
      draw_outlines(view, found, canvas);
      if (Status w = platform::write_pgm(drawn[i], canvas.view(), inputs); !w)
        exit_code = fail("detect: --draw " + w.message());
    }
  }
  return exit_code;
}

}  // namespace kg::cli
