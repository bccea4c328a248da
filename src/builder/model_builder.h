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

#include "core/description/arc_types.h"
#include "keygraph/model_index.h"
#include "keygraph/params.h"
#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg {

// What one view of a model contributed (reports, keygraph build).
struct ViewSummary {
  double scale = 1.0, tilt = 1.0, longitude = 0.0;  // builder/model_views.h
  double blur = 0.0;            // > 0: a small view's blurred twin (ModelView::blur)
  bool glow = false;            // a small view's glowing twin (ModelView::glow)
  int width = 0, height = 0;    // view image size
  int keypoints = 0;            // detected inside the model
  int arcs = 0;                 // stored (after deduplication)
  int view_arcs = 0;            // described in it (before deduplication)
  std::uint64_t keygraphs = 0;  // keygraphs over the view's own arcs
};

struct BuiltModel {
  std::string name;
  int width = 0;
  int height = 0;
  std::vector<Point2f> keypoints;      // model pixels
  std::vector<float> keypoint_scales;  // detector sigma per keypoint (0: unknown)
  // Finest and coarsest view scale code (core/index/index_format.h) per keypoint.
  std::vector<std::array<std::uint8_t, 2>> keypoint_views;
  // Params::descriptor.vertex_descriptor kSift: kVertexDescriptorSize bytes
  // per keypoint, in keypoint order; empty for kNone.
  std::vector<std::uint8_t> vertex_descriptors;
  std::vector<ModelArc> arcs;              // local keypoint ids, sorted by (from, to)
  std::vector<ArcDescriptor> descriptors;  // one per arc
  // Scale attributes per arc (core/description/arc_attributes.h), measured in the view
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

}  // namespace kg
