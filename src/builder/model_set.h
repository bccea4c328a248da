// A set of model images to build keygraph models from, and the one
// function that builds them: `keygraph build` and `keygraph eval --truth`
// both go through build_model_set(), so that an option of how models are
// built (ModelBuildOptions) reaches both.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "builder/model_builder.h"
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

// Loads every source (its ROI cut out) and builds its model. Names must be
// non-empty and distinct; an ROI must lie inside its image. `grays` gets
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
