// keygraph.build()'s way into the desktop builder: one C function, loaded
// by ctypes with the C API from the same shared library
// (libkeygraph_python.so). It does what `keygraph build` does
// (src/cli/cmd_build.cpp) through the same builder calls, so the same
// images and parameters give the same index, byte for byte: every model
// built (builder/model_set.h), the quality report measured and stored, the
// file written whole or not at all. Nothing may escape to ctypes: OpenCV's
// exceptions become an error message.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "builder/image_io.h"
#include "builder/index_writer.h"
#include "builder/model_quality.h"
#include "builder/model_set.h"
#include "keygraph/param_text.h"
#include "platform/files/output_file.h"

namespace {

// Images handed over as arrays, by the key their ModelSource carries
// (build_model_set() takes a plain function as its loader). One build at a
// time holds them: g_build_lock.
std::mutex g_build_lock;
std::map<std::string, cv::Mat> g_arrays;
constexpr char kArrayKey[] =
    "\x1f"
    "array ";  // no file name starts so

kg::Status load_source(const std::string& key, cv::Mat& gray) {
  if (key.rfind(kArrayKey, 0) == 0) {
    const auto it = g_arrays.find(key);
    if (it == g_arrays.end()) return {kg::StatusCode::kNotFound, "image array missing"};
    gray = it->second;
    return kg::Status::ok();
  }
  return kg::load_gray(key, gray);
}

int fail(const kg::Status& s, char* error, std::size_t error_size) {
  if (error != nullptr && error_size > 0) {
    std::strncpy(error, s.message().c_str(), error_size - 1);
    error[error_size - 1] = '\0';
  }
  return static_cast<int>(s.code());
}

kg::Status build(const char* output, int count, const char* const* paths,
                 const std::uint8_t* const* pixels, const int* widths, const int* heights,
                 const std::ptrdiff_t* strides, const int* rois, const char* const* names,
                 int param_count, const char* const* param_names, const char* const* param_values,
                 const char* preset, int threads, int look_alikes) {
  using kg::Status;
  using kg::StatusCode;
  if (output == nullptr || count <= 0 || paths == nullptr || pixels == nullptr || names == nullptr)
    return {StatusCode::kInvalidArgument, "build: no output or no images"};
  kg::ModelBuildOptions options;
  if (preset != nullptr && preset[0] != '\0') {
    if (Status s = kg::preset_params(preset, options.params); !s) return s;
  }
  for (int i = 0; i < param_count; ++i) {
    if (Status s = kg::set_param(options.params, param_names[i], param_values[i]); !s) return s;
  }
  options.threads = threads;
  std::vector<kg::ModelSource> sources(static_cast<std::size_t>(count));
  std::vector<std::string> inputs;
  g_arrays.clear();
  for (int i = 0; i < count; ++i) {
    kg::ModelSource& source = sources[static_cast<std::size_t>(i)];
    source.name = names[i] == nullptr ? "" : names[i];
    if (paths[i] != nullptr) {
      source.path = paths[i];
      inputs.push_back(source.path);
    } else {
      source.path = kArrayKey + std::to_string(i);
      g_arrays[source.path] =
          cv::Mat(heights[i], widths[i], CV_8UC1, const_cast<std::uint8_t*>(pixels[i]),
                  static_cast<std::size_t>(strides[i]));
    }
    if (rois != nullptr && rois[4 * i + 2] > 0)
      source.roi = cv::Rect(rois[4 * i], rois[4 * i + 1], rois[4 * i + 2], rois[4 * i + 3]);
  }
  // The output first, as `keygraph build` does: a bad path fails before the build.
  kg::platform::OutputFile out;
  if (Status s = out.create(output, inputs); !s) return s;
  std::vector<cv::Mat> grays;
  std::vector<kg::BuiltModel> models;
  Status built = kg::build_model_set(sources, options, load_source, grays, models);
  if (built) {
    kg::QualityOptions quality_options;
    quality_options.look_alikes = look_alikes != 0;
    quality_options.threads = threads;
    kg::QualityReport quality;
    built = kg::measure_quality(models, grays, options.params, quality_options, quality);
    if (built) built = kg::write_index(models, options.params, out, &quality);
  }
  g_arrays.clear();
  return built;
}

}  // namespace

extern "C" {

// Builds the index `output` from `count` model images: image i is the file
// paths[i], or (paths[i] NULL) the 8-bit grey array pixels[i] of
// widths[i] x heights[i] with row stride strides[i]; rois[4i..4i+3] its
// x, y, width, height (width 0: the whole image; rois may be NULL); names[i]
// its model name. Parameters: the preset (NULL or "": the defaults), then
// each param_names[k] = param_values[k] (keygraph/param_text.h). threads 0:
// one per CPU. Returns 0 (kg::StatusCode::kOk) or the error's code with its
// message in `error`.
__attribute__((visibility("default"))) int kgpy_build(
    const char* output, int count, const char* const* paths, const std::uint8_t* const* pixels,
    const int* widths, const int* heights, const std::ptrdiff_t* strides, const int* rois,
    const char* const* names, int param_count, const char* const* param_names,
    const char* const* param_values, const char* preset, int threads, int look_alikes, char* error,
    std::size_t error_size) {
  const std::lock_guard<std::mutex> lock(g_build_lock);
  try {
    const kg::Status s =
        build(output, count, paths, pixels, widths, heights, strides, rois, names, param_count,
              param_names, param_values, preset, threads, look_alikes);
    return s ? 0 : fail(s, error, error_size);
  } catch (const std::exception& e) {
    g_arrays.clear();
    return fail({kg::StatusCode::kInvalidArgument, std::string("build: ") + e.what()}, error,
                error_size);
  }
}

}  // extern "C"
