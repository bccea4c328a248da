// keygraph demo [-o DIR]: the Quick start's main job. Builds an index of
// box.png from Debian's opencv-doc images, finds the box in
// box_in_scene.png, prints where, and draws the outline. Without -o it
// writes into a directory of its own under the system's temporary
// directory, so that a demo run from a checkout leaves nothing there.
#include <sys/stat.h>
#include <unistd.h>

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

namespace {

// The default output directory: keygraph-demo-<uid> in the temporary
// directory, made if missing; an existing one must be a directory of this
// user's (not a link someone else planted in a shared /tmp).
Status default_demo_dir(std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path tmp = fs::temp_directory_path(ec);
  if (ec)
    return {StatusCode::kIoError, "no temporary directory (" + ec.message() + "); give -o DIR"};
  dir = (tmp / ("keygraph-demo-" + std::to_string(::getuid()))).string();
  fs::create_directory(dir, ec);
  struct stat info {};
  if (::lstat(dir.c_str(), &info) != 0 || !S_ISDIR(info.st_mode) || info.st_uid != ::getuid())
    return {StatusCode::kIoError, dir + " is not a directory of this user's; give -o DIR"};
  return Status::ok();
}

}  // namespace

int cmd_demo(const Args& args) {
  std::string out_dir;
  std::string data_dir = KG_OPENCV_DATA_DIR;
  Options options("demo", "[-o DIR] [--data DIR]",
                  "Builds an index of box.png from Debian's opencv-doc images, finds the box in\n"
                  "box_in_scene.png, prints where, and draws the outline (DIR/demo.png).");
  options
      .text("-o, --out, --output", "DIR", out_dir,
            "where demo.kgi and demo.png are written, an existing directory (default:\n"
            "keygraph-demo-<user id> in the temporary directory, made if missing)")
      .text("--data", "DIR", data_dir, "where box.png and box_in_scene.png are")
      .example("keygraph demo")
      .example("keygraph demo -o /tmp");
  if (const int exit_code = options.parse(args); exit_code >= 0) return exit_code;
  const std::string model_path = data_dir + "/box.png";
  const std::string scene_path = data_dir + "/box_in_scene.png";
  std::error_code ec;
  if (out_dir.empty()) {
    if (Status s = default_demo_dir(out_dir); !s) return fail(s.message());
  } else if (!std::filesystem::is_directory(out_dir, ec)) {
    return fail("no directory " + out_dir);
  }

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
  cv::Mat picture_in_colour;
  if (!load_color(scene_path, picture_in_colour)) picture_in_colour = scene;
  if (!write_image_atomically(picture, draw_scene(picture_in_colour, found),
                              {model_path, scene_path}, error))
    return fail(error);
  std::printf("wrote %s\n", picture.c_str());
  return found.empty() ? 1 : 0;
}

}  // namespace kg::cli
