// keygraph detect: its options are the Options table below (keygraph detect --help).
// The device build's detect: scenes read by platform/files (binary PGM;
// more formats when that library was built with OpenCV), the core detector,
// and the same output as the desktop detect. --draw writes PGM (outlines
// and names in the built-in font of bitmap_font.h).
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

DetectCommand::DetectCommand(const std::string& draw_format)
    : options_("detect",
               "--index I.kgi [--json] [--draw DIR|OUT] [--set NAME=VALUE]... [--threads N]\n"
               "       SCENE...",
               "Finds the index's models in scene images: per scene, the detections with their\n"
               "inliers, score and corners (scene pixels), and the time.") {
  const bool pgm = draw_format == "PGM";
  options_
      .positional("SCENE...", "scene image files, or directories of them (name order)",
                  [this](const std::string& v) {
                    scene_args_.push_back(v);
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
  settings.declare(options_);
  options_
      .example(std::string("keygraph detect --index signs.kgi --draw found/ ") +
               (pgm ? "frames/" : "photos/"))
      .example("keygraph detect --index signs.kgi --threads 4 --set min_confidence=0.5 " +
               std::string(pgm ? "frames/" : "photos/"))
      .example("keygraph detect --index signs.kgi --json " +
               std::string(pgm ? "scene.pgm" : "scene.jpg"));
}

int DetectCommand::parse(const Args& args, const std::string& draw_ext,
                         const std::function<bool(const std::string&)>& writable,
                         const std::string& unwritable_hint) {
  if (const int exit_code = options_.parse(args); exit_code >= 0) return exit_code;
  if (index_path.empty()) return options_.usage_error("no index given (--index I.kgi)");
  if (scene_args_.empty()) return options_.usage_error("no scene images given");
  if (std::string error = expand_scene_paths(scene_args_, scenes); !error.empty())
    return fail(error);
  inputs = scenes;
  inputs.push_back(index_path);
  // Every picture is checked before the first scene (draw_targets.h).
  if (!draw.empty()) {
    if (std::string error = plan_drawings(draw, scenes, draw_ext, writable, inputs, drawn);
        !error.empty())
      return fail(error + (writable(draw) ? "" : unwritable_hint));
  }
  return -1;
}

int cmd_detect_files(const Args& args) {
  DetectCommand command("PGM");
  const auto writable = [](const std::string& path) {
    return std::filesystem::path(path).extension() == ".pgm";
  };
  if (const int exit_code =
          command.parse(args, ".pgm", writable, " (this build writes PGM only: a .pgm name)");
      exit_code >= 0)
    return exit_code;
  // Read into memory, not mapped: an index changed in place meanwhile
  // cannot crash the process (model_index.h).
  ModelIndex index;
  if (Status s = ModelIndex::read(command.index_path, index); !s) return fail(s.message());
  if (const std::string problem = core_detector_problem(index); !problem.empty())
    return fail(command.index_path + ": " + problem);

  DetectOptions runtime;
  if (Status s = command.settings.options_for(index, runtime); !s)
    return command.usage_error(s.message());
  Detector detector(index, command.settings.limits(), runtime);
  DetectionList found;
  platform::GrayImage scene_image, canvas;
  int exit_code = 0;
  for (std::size_t i = 0; i < command.scenes.size(); ++i) {
    const std::string& scene = command.scenes[i];
    if (Status s = platform::read_image(scene, scene_image); !s) {
      exit_code = scene_failed(scene, s.message(), command.json);
      continue;
    }
    const ImageView view = scene_image.view();
    if (const Status fit = fit_detector(detector, view); !fit) {
      exit_code = scene_failed(scene, scene + ": " + fit.message(), command.json);
      continue;
    }
    const auto start = std::chrono::steady_clock::now();
    const Status s = detector.detect(view, found);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (!s) {
      exit_code = scene_failed(scene, scene + ": " + s.message(), command.json);
      continue;
    }
    print_detections(scene, view, ms, found, detector.stats(), command.json);
    std::fflush(stdout);
    if (!command.draw.empty()) {
      draw_outlines(view, found, canvas);
      if (Status w = platform::write_pgm(command.drawn[i], canvas.view(), command.inputs); !w)
        exit_code = fail("--draw " + w.message());
    }
  }
  return exit_code;
}

}  // namespace kg::cli
