// keygraph detect: its options are the Options table below (keygraph detect --help).
// The device build's detect: scenes read by platform/files (binary PGM;
// more formats when that library was built with OpenCV), the core detector,
// and the same output as the desktop detect. --draw writes PGM (outlines,
// no names: there is no font without OpenCV).
#include <chrono>
#include <filesystem>

#include "cli/device/detector_fit.h"
#include "cli/device/device_commands.h"
#include "cli/device/draw_targets.h"
#include "cli/device/frame_output.h"
#include "cli/device/options.h"
#include "cli/device/scene_list.h"
#include "keygraph/detector.h"
#include "platform/files/file_source.h"
#include "platform/files/pgm.h"

namespace kg::cli {

Options detect_options(std::string& index_path, std::string& draw, bool& json,
                       std::vector<std::string>& scenes, DetectSettings& settings,
                       const std::string& draw_format) {
  const bool pgm = draw_format == "PGM";
  Options options("detect",
                  "--index I.kgi [--json] [--draw DIR|OUT] [--set NAME=VALUE]... [--threads N]\n"
                  "       SCENE...",
                  "Finds the index's models in scene images: per scene, the detections with their\n"
                  "inliers, score and corners (scene pixels), and the time.");
  options
      .positional("SCENE...", "scene image files, or directories of them (name order)",
                  [&scenes](const std::string& v) {
                    scenes.push_back(v);
                    return std::string();
                  })
      .text("--index", "I.kgi", index_path, "the model index (required)")
      .flag("--json", json,
            "one JSON object per scene on stdout; a scene that fails gives\n"
            "{\"scene\": ..., \"error\": ...}")
      .text("--draw", "DIR|OUT", draw,
            "draw what was found (" + draw_format +
                "): into DIR, an existing directory, one picture per scene named after it;\n"
                "or into the file OUT for one scene (OUT_<scene name> beside it for several)");
  settings.declare(options);
  options
      .example(std::string("keygraph detect --index signs.kgi --draw found/ ") +
               (pgm ? "frames/" : "photos/"))
      .example("keygraph detect --index signs.kgi --threads 4 --set min_confidence=0.5 " +
               std::string(pgm ? "frames/" : "photos/"))
      .example("keygraph detect --index signs.kgi --json " +
               std::string(pgm ? "scene.pgm" : "scene.jpg"));
  return options;
}

int cmd_detect_files(const Args& args) {
  std::string index_path, draw;
  bool json = false;
  std::vector<std::string> scene_args, scenes;
  DetectSettings settings;
  Options options = detect_options(index_path, draw, json, scene_args, settings, "PGM");
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
    const auto writable = [](const std::string& path) {
      return std::filesystem::path(path).extension() == ".pgm";
    };
    if (std::string error = plan_drawings(draw, scenes, ".pgm", writable, inputs, drawn);
        !error.empty())
      return fail(error + (writable(draw) ? "" : " (this build writes PGM only: a .pgm name)"));
  }
  // Read into memory, not mapped: an index changed in place meanwhile
  // cannot crash the process (model_index.h).
  ModelIndex index;
  if (Status s = ModelIndex::read(index_path, index); !s) return fail(s.message());
  if (const std::string problem = core_detector_problem(index); !problem.empty())
    return fail(index_path + ": " + problem);

  DetectOptions runtime;
  if (Status s = settings.options_for(index, runtime); !s) return options.usage_error(s.message());
  Detector detector(index, settings.limits(), runtime);
  DetectionList found;
  platform::GrayImage scene_image, canvas;
  int exit_code = 0;
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    const std::string& scene = scenes[i];
    if (Status s = platform::read_image(scene, scene_image); !s) {
      exit_code = scene_failed(scene, s.message(), json);
      continue;
    }
    const ImageView view = scene_image.view();
    if (const Status fit = fit_detector(detector, view); !fit) {
      exit_code = scene_failed(scene, scene + ": " + fit.message(), json);
      continue;
    }
    const auto start = std::chrono::steady_clock::now();
    const Status s = detector.detect(view, found);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (!s) {
      exit_code = scene_failed(scene, scene + ": " + s.message(), json);
      continue;
    }
    print_detections(scene, view, ms, found, detector.stats(), json);
    std::fflush(stdout);
    if (!draw.empty()) {
      draw_outlines(view, found, canvas);
      if (Status w = platform::write_pgm(drawn[i], canvas.view(), inputs); !w)
        exit_code = fail("--draw " + w.message());
    }
  }
  return exit_code;
}

}  // namespace kg::cli
