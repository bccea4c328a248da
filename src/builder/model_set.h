// A set of model images to build keygraph models from, and the one
// function that builds them: `keygraph build` and `keygraph eval --truth`
// both go through build_model_set(), so that an option of how models are
// built (ModelBuildOptions) reaches both.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "builder/model_builder.h"
#include "builder/models_json.h"
#include "builder/progress.h"
#include "keygraph/params.h"
#include "keygraph/status.h"

namespace kg {

struct ModelSource {
  std::string name;
  std::string path;
  std::optional<cv::Rect> roi;  // the model is this rectangle of the image
};

struct ModelBuildOptions {
  Params params;
  // Models built at once, each on its own thread (0: one per CPU the
  // process may use). The index is the same for any count.
  int threads = 0;
};

// Loads an image file as 8-bit gray (the CLI passes its own, quieter one).
using ImageLoader = Status (*)(const std::string& path, cv::Mat& gray);

// Loads one source's image, its ROI cut out (which must lie inside it).
Status load_model_image(const ModelSource& source, ImageLoader load, cv::Mat& gray);

// What building a set takes, per pixel of its model images: every image
// and every built model are in memory until the index is written, and a
// model's data grows with its image (measured: 40 copies of opencv-doc's
// box.png, 2.9 million pixels, peak at 530 MB; graf1.png alone, 0.5
// million, 100 MB above the process's own). A set whose images would need
// more than three quarters of what the process may still take (its
// address-space limit, at most the machine's memory) is refused while its
// images are loaded, before it has taken that memory; so is one of more
// than kMaxModels (builder/models_json.h) models.
inline constexpr std::uint64_t kBuildBytesPerModelPixel = 200;

// Loads every source's image (its ROI cut out) into `grays`, in order,
// after checking the names (non-empty, distinct) and their count (at most
// kMaxModels); the images together within the memory their models need
// (kBuildBytesPerModelPixel) and, when `views` is given, each thick enough
// for its tilted views (check_view_canvas(), builder/model_views.h). On
// failure `grays` is empty and the status names the first bad source.
Status load_model_images(const std::vector<ModelSource>& sources, const ViewParams* views,
                         ImageLoader load, std::vector<cv::Mat>& grays);

// Loads every source (load_model_images()) and builds its model. `grays` gets
// the model images (after the ROI), `models` the built models, in order.
// `progress` (may be empty) is called after each model, with its name, in
// the order they finish (one call at a time). Every name and image is
// checked before any model is built: on failure `grays` and `models` are
// empty and the status is the first bad name or image's, else the first
// source's (in order) whose model failed to build.
Status build_model_set(const std::vector<ModelSource>& sources, const ModelBuildOptions& options,
                       ImageLoader load, std::vector<cv::Mat>& grays,
                       std::vector<BuiltModel>& models, const ProgressFn& progress = {});

// Model sources from a directory or a models.json file (docs/EVAL.md): a
// directory with a models.json uses it; otherwise every image in it is a
// model named after the file's stem. models.json maps names to files
// (relative to it), each either "file.png" or {"file": "file.png",
// "roi": [x, y, w, h]}.
Status read_model_sources(const std::string& path, std::vector<ModelSource>& out);

}  // namespace kg
