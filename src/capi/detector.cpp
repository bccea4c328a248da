// kg_detector: a kg::Detector with its limits and runtime options, and the
// frame's entry point, which copies the detections into the caller's array.
#include <cstring>
#include <new>
#include <string_view>

#include "capi/handles.h"

namespace {

using kg::capi::fail;

kg::Limits to_limits(const kg_limits* limits) {
  kg::Limits out;
  if (limits == nullptr) return out;
  out.max_width = limits->max_width;
  out.max_height = limits->max_height;
  out.max_keypoints = limits->max_keypoints;
  out.max_scene_keypoints = limits->max_scene_keypoints;
  out.max_arc_matches = limits->max_arc_matches;
  out.max_arc_pool = limits->max_arc_pool;
  out.max_correspondences = limits->max_correspondences;
  out.max_detections = limits->max_detections;
  out.threads = limits->threads;
  return out;
}

// The new handle in `out` when its detector was constructed; else its
// status, and nothing kept.
kg_status keep(kg_detector* handle, kg_detector** out) {
  if (handle == nullptr)
    return fail(KG_RESOURCE_EXHAUSTED, "out of memory for the detector handle");
  if (const kg::Status& s = handle->detector.status(); !s) {
    const kg_status code = fail(s);
    delete handle;
    return code;
  }
  *out = handle;
  return KG_OK;
}

// The options in effect with the model selection, which options() leaves out.
kg::DetectOptions current_options(const kg_detector& d) {
  kg::DetectOptions options = d.detector.options();
  options.models = d.models.empty() ? nullptr : d.models.data();
  options.model_count = d.models.size();
  return options;
}

}  // namespace

namespace kg::capi {

std::size_t copy_detections(const kg_index& index, const DetectionList& found, kg_detection* out,
                            std::size_t capacity, bool& truncated) {
  const std::size_t n = found.size() < capacity ? found.size() : capacity;
  for (std::size_t i = 0; i < n; ++i) {
    const Detection& from = found[i];
    kg_detection& to = out[i];
    to.model_id = from.model_id;
    to.model_name = kg_index_model_name(&index, from.model_id);
    for (int k = 0; k < 9; ++k) to.homography[k] = from.homography[static_cast<std::size_t>(k)];
    for (int c = 0; c < 4; ++c) {
      to.corners[c][0] = from.corners[c].x;
      to.corners[c][1] = from.corners[c].y;
    }
    to.inliers = from.inliers;
    to.inlier_keygraphs = from.inlier_keygraphs;
    to.score = from.score;
    to.chance = from.chance;
    to.rms_error = from.rms_error;
    to.verification_z = from.verification_z;
    to.appearance = from.appearance;
    to.confidence = from.confidence;
    to.ransac_iterations = from.ransac_iterations;
    to.track_id = from.track_id;
    to.tracked = from.tracked ? 1 : 0;
  }
  truncated = n < found.size();
  return n;
}

kg_status frame_arguments(const void* handle, const kg_image* image, const kg_detection* out,
                          std::size_t capacity, std::size_t* count, const char* null_message,
                          ImageView& view) {
  if (count != nullptr) *count = 0;
  if (handle == nullptr || image == nullptr || count == nullptr || (out == nullptr && capacity > 0))
    return fail(KG_INVALID_ARGUMENT, null_message);
  if (image->data == nullptr) return fail(KG_INVALID_ARGUMENT, "image data is NULL");
  if (image->width <= 0 || image->height <= 0 || image->stride < image->width)
    return fail(KG_INVALID_ARGUMENT,
                "bad image layout (width and height must be > 0, stride >= width)");
  view = ImageView(image->data, image->width, image->height, image->stride);
  return KG_OK;
}

}  // namespace kg::capi

extern "C" {

void kg_limits_default(kg_limits* out) {
  if (out == nullptr) return;
  const kg::Limits l;
  *out = kg_limits{l.max_width,           l.max_height,      l.max_keypoints,
                   l.max_scene_keypoints, l.max_arc_matches, l.max_arc_pool,
                   l.max_correspondences, l.max_detections,  l.threads};
}

kg_status kg_detector_create(const kg_index* index, const kg_limits* limits, kg_detector** out) {
  if (out == nullptr) return fail(KG_INVALID_ARGUMENT, "kg_detector_create: out is NULL");
  *out = nullptr;
  if (index == nullptr) return fail(KG_INVALID_ARGUMENT, "kg_detector_create: index is NULL");
  return keep(new (std::nothrow) kg_detector(*index, to_limits(limits)), out);
}

size_t kg_detector_workspace_bytes(const kg_index* index, const kg_limits* limits) {
  if (index == nullptr) return 0;
  return kg::Detector::workspace_bytes(index->index, to_limits(limits));
}

kg_status kg_detector_create_in(const kg_index* index, const kg_limits* limits, void* buffer,
                                size_t size, kg_detector** out) {
  if (out == nullptr) return fail(KG_INVALID_ARGUMENT, "kg_detector_create_in: out is NULL");
  *out = nullptr;
  if (index == nullptr) return fail(KG_INVALID_ARGUMENT, "kg_detector_create_in: index is NULL");
  if (buffer == nullptr) return fail(KG_INVALID_ARGUMENT, "kg_detector_create_in: buffer is NULL");
  return keep(new (std::nothrow) kg_detector(*index, to_limits(limits), buffer, size), out);
}

void kg_detector_destroy(kg_detector* detector) {
  delete detector;
}

kg_status kg_detector_set_option(kg_detector* detector, const char* name, const char* value) {
  if (detector == nullptr || name == nullptr || value == nullptr)
    return fail(KG_INVALID_ARGUMENT, "kg_detector_set_option: NULL argument");
  kg::DetectOptions options = current_options(*detector);
  if (kg::Status s = kg::set_detect_option(options, name, value); !s) return fail(s);
  if (kg::Status s = detector->detector.set_options(options); !s) return fail(s);
  return KG_OK;
}

kg_status kg_detector_set_models(kg_detector* detector, const int32_t* ids, size_t count) {
  if (detector == nullptr)
    return fail(KG_INVALID_ARGUMENT, "kg_detector_set_models: detector is NULL");
  if (ids == nullptr && count > 0)
    return fail(KG_INVALID_ARGUMENT, "kg_detector_set_models: ids is NULL");
  kg::DetectOptions options = current_options(*detector);
  options.models = count == 0 ? nullptr : ids;
  options.model_count = count;
  if (kg::Status s = detector->detector.set_options(options); !s) return fail(s);
  detector->models.assign(ids, ids + count);
  return KG_OK;
}

kg_status kg_detect(kg_detector* detector, const kg_image* image, kg_detection* out,
                    size_t capacity, size_t* count) {
  if (detector != nullptr) detector->caller_truncated = false;
  kg::ImageView frame;
  if (const kg_status s = kg::capi::frame_arguments(detector, image, out, capacity, count,
                                                    "kg_detect: NULL argument", frame);
      s != KG_OK)
    return s;
  if (kg::Status s = detector->detector.detect(frame, detector->found); !s) return fail(s);
  // kg_detector_stats() reports a cut by the caller's capacity.
  *count = kg::capi::copy_detections(*detector->index, detector->found, out, capacity,
                                     detector->caller_truncated);
  return KG_OK;
}

kg_status kg_detector_stats(const kg_detector* detector, kg_stats* out) {
  if (detector == nullptr || out == nullptr)
    return fail(KG_INVALID_ARGUMENT, "kg_detector_stats: NULL argument");
  const kg::DetectStats& s = detector->detector.stats();
  std::memset(out, 0, sizeof *out);
  out->keypoints = s.keypoints;
  out->sampled_keypoints = s.sampled_keypoints;
  out->keygraphs = s.keygraphs;
  out->arcs_described = s.arcs_described;
  out->arc_matches = s.arc_matches;
  out->correspondences = s.correspondences;
  out->ransac_iterations = s.ransac_iterations;
  out->truncated_keypoints = s.truncated_keypoints ? 1 : 0;
  out->truncated_arc_matches = s.truncated_arc_matches ? 1 : 0;
  out->truncated_correspondences = s.truncated_correspondences ? 1 : 0;
  out->truncated_detections = s.truncated_detections || detector->caller_truncated ? 1 : 0;
  out->ms_keypoints = s.ms_keypoints;
  out->ms_graph = s.ms_graph;
  out->ms_describe = s.ms_describe;
  out->ms_select = s.ms_select;
  out->ms_pose = s.ms_pose;
  out->stopped_early = s.stopped_early;
  return KG_OK;
}

}  // extern "C"
