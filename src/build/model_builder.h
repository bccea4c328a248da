// Desktop side of the pipeline (paper sections 5-6, model half): keypoints
// of a model image over several scales, every model arc (Chebyshev distance
// within [min, max]) with its descriptor, optionally the keypoints' SIFT
// descriptors, and the keygraph count; then one .kgi index for a set of
// models.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "keygraph/model_index.h"
#include "keygraph/params.h"
#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg {

namespace platform {
class OutputFile;
}  // namespace platform

// What one view of a model contributed (reports, keygraph build).
struct ViewSummary {
  double scale = 1.0, tilt = 1.0, longitude = 0.0;  // build/model_views.h
  int width = 0, height = 0;                        // view image size
  int keypoints = 0;                                // detected inside the model
  int arcs = 0;                                     // stored (after deduplication)
  int view_arcs = 0;                                // described in it (before deduplication)
  std::uint64_t keygraphs = 0;                      // keygraphs over the view's own arcs
};

struct BuiltModel {
  std::string name;
  int width = 0;
  int height = 0;
  std::vector<Point2f> keypoints;      // model pixels
  std::vector<float> keypoint_scales;  // detector sigma per keypoint (0: unknown)
  // Finest and coarsest view scale code (core/index_format.h) per keypoint.
  std::vector<std::array<std::uint8_t, 2>> keypoint_views;
  // Params::descriptor.vertex_descriptor kSift: kVertexDescriptorSize bytes
  // per keypoint, in keypoint order; empty for kNone.
  std::vector<std::uint8_t> vertex_descriptors;
  std::vector<ModelArc> arcs;              // local keypoint ids, sorted by (from, to)
  std::vector<ArcDescriptor> descriptors;  // one per arc
  // Scale attributes per arc (core/arc_attributes.h), measured in the view
  // that described it.
  std::vector<std::array<float, 2>> arc_attributes;
  std::vector<ViewSummary> views;
  std::uint64_t keygraphs = 0;
  // The model's appearance (ModelAppearance, format 6.2): the model image
  // downsampled by area averaging to Params::views.appearance_size pixels
  // on its long edge (never upsampled), 8-bit grey; empty when that is 0.
  cv::Mat appearance;
  float appearance_scale = 0.f;  // appearance pixels per model pixel
};

// The model image resampled by area averaging with one scale on both axes,
// so that its long edge is `size` pixels, or a copy of it when it is not
// larger than that: the appearance BuiltModel stores; `scale` is its
// pixels per model pixel.
void model_appearance(const cv::Mat& gray, int size, cv::Mat& out, float& scale);

// Builds one model from an 8-bit gray image.
Status build_model(const cv::Mat& gray, const std::string& name, const Params& params,
                   BuiltModel& out);

// The quality report of an index's models (format sections 12-14;
// build/model_quality.h measures it): one record per model, the views of
// all models consecutive, look-alike pairs sorted.
struct QualityReport {
  std::vector<ModelQuality> models;
  std::vector<ViewQuality> views;
  std::vector<LookAlike> look_alikes;
};

// Serialises models into the .kgi layout (docs/FORMAT.md). Deterministic.
// Without `quality` the quality sections are written empty (no report).
Status serialize_index(const std::vector<BuiltModel>& models, const Params& params,
                       std::vector<std::uint8_t>& bytes, const QualityReport* quality = nullptr);

// Writes the index to `path` through a platform::OutputFile
// (platform/files/output_file.h): a unique temporary renamed into place, so
// a failure or an interrupt never leaves a partial index behind, and never
// over anything but a regular file.
Status write_index(const std::vector<BuiltModel>& models, const Params& params,
                   const std::string& path, const QualityReport* quality = nullptr);
// The same into an output created beforehand (e.g. before a long build, so
// that a bad output path fails at once); commits it.
Status write_index(const std::vector<BuiltModel>& models, const Params& params,
                   platform::OutputFile& out, const QualityReport* quality = nullptr);

}  // namespace kg
