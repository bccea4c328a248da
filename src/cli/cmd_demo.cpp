// keygraph demo [--out DIR]: the Quick start's main job. Builds an index of
// box.png from Debian's opencv-doc images, finds the box in
// box_in_scene.png, prints where, and draws the outline.
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "builder/desktop_detect.h"
#include "builder/image_io.h"
#include "builder/index_writer.h"
#include "builder/model_builder.h"
#include "cli/commands.h"
#include "cli/device/options.h"

namespace kg::cli {

int cmd_demo(const Args& args) {
  std::string out_dir = ".";
  std::string data_dir = KG_OPENCV_DATA_DIR;
  Options options("demo", "[--out DIR] [--data DIR]",
                  "Builds an index of box.png from Debian's opencv-doc images, finds the box in\n"
                  "box_in_scene.png, prints where, and draws the outline (DIR/demo.png).");
  options.text("--out", "DIR", out_dir, "where demo.kgi and demo.png are written")
      .text("--data", "DIR", data_dir, "where box.png and box_in_scene.png are")
      .example("keygraph demo --out /tmp");
  if (const int exit_code = options.parse(args); exit_code >= 0) return exit_code;
  const std::string model_path = data_dir + "/box.png";
  const std::string scene_path = data_dir + "/box_in_scene.png";
  std::error_code ec;
  if (!std::filesystem::is_directory(out_dir, ec)) return fail("demo: no directory " + out_dir);

  cv::Mat model_image, scene;
  Status s = load_image(model_path, model_image);
  if (!s) return fail(s.message() + " (install Debian's opencv-doc package)");
  s = load_image(scene_path, scene);
  if (!s) return fail(s.message() + " (install Debian's opencv-doc package)");

  Params params;
  std::vector<BuiltModel> models(1);
  s = build_model(model_image, "box", params, models[0]);
  if (!s) return fail(s.message());
  const std::string index_path = out_dir + "/demo.kgi";
  s = write_index(models, params, index_path);
  if (!s) return fail(s.message());
  std::printf("model box (%s): %zu keypoints, %zu arcs, %llu keygraphs -> %s\n", model_path.c_str(),
              models[0].keypoints.size(), models[0].arcs.size(),
              static_cast<unsigned long long>(models[0].keygraphs), index_path.c_str());

  ModelIndex index;
  s = ModelIndex::read(index_path, index);
  if (!s) return fail(s.message());
  DesktopDetector detector(index);
  DetectionList found;
  const auto start = std::chrono::steady_clock::now();
  s = detector.detect(scene, found);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (!s) return fail(s.message());
  std::printf("scene %s (%dx%d): %zu detection(s) in %.1f ms\n", scene_path.c_str(), scene.cols,
              scene.rows, found.size(), ms);
  for (const Detection& d : found) {
    std::printf("  %.*s: %d inlier keypoints, corners", static_cast<int>(d.model_name.size()),
                d.model_name.data(), d.inliers);
    for (const Point2f& c : d.corners) std::printf(" (%.1f, %.1f)", c.x, c.y);
    std::printf("\n");
  }
  const std::string picture = out_dir + "/demo.png";
  std::string error;
  if (!write_image_atomically(picture, draw_detections(scene, found), {model_path, scene_path},
                              error))
    return fail(error);
  std::printf("wrote %s\n", picture.c_str());
  return found.empty() ? 1 : 0;
}

}  // namespace kg::cli
