// kg_tracker: a kg::Tracker over a detector handle.
#include <cstring>
#include <new>

#include "capi/handles.h"

namespace {

using kg::capi::fail;

kg::TrackerOptions to_options(const kg_tracker_options* options) {
  kg::TrackerOptions out;
  if (options == nullptr) return out;
  out.detect_interval = options->detect_interval;
  out.min_correlation = options->min_correlation;
  out.max_tracks = options->max_tracks;
  out.smoothing = options->smoothing;
  return out;
}

// Whether the tracker's status only says that it cannot follow objects
// (an index without appearances; it detects every frame: keygraph/
// tracker.h), the one status of a made tracker that is no error. The C++
// Tracker checks the options first, so that status is what a tracker with
// the default options reports, and only when these options are good.
bool detects_only(const kg_tracker& t) {
  const kg::Detector& detector = t.detector->detector;
  if (t.tracker.status() || !detector.status() || detector.index().has_appearance()) return false;
  const kg::Tracker probe(t.detector->detector);
  return !probe.status() && probe.status().message() == t.tracker.status().message();
}

}  // namespace

extern "C" {

void kg_tracker_options_default(kg_tracker_options* out) {
  if (out == nullptr) return;
  const kg::TrackerOptions o;
  *out = kg_tracker_options{o.detect_interval, o.min_correlation, o.max_tracks, o.smoothing};
}

kg_status kg_tracker_create(kg_detector* detector, const kg_tracker_options* options,
                            kg_tracker** out) {
  if (out == nullptr) return fail(KG_INVALID_ARGUMENT, "kg_tracker_create: out is NULL");
  *out = nullptr;
  if (detector == nullptr) return fail(KG_INVALID_ARGUMENT, "kg_tracker_create: detector is NULL");
  auto* handle = new (std::nothrow) kg_tracker(*detector, to_options(options));
  if (handle == nullptr) return fail(KG_RESOURCE_EXHAUSTED, "out of memory for the tracker handle");
  if (!handle->tracker.status() && !detects_only(*handle)) {
    const kg_status code = fail(handle->tracker.status());
    delete handle;
    return code;
  }
  *out = handle;
  return KG_OK;
}

void kg_tracker_destroy(kg_tracker* tracker) {
  delete tracker;
}

int kg_tracker_can_track(const kg_tracker* tracker) {
  return tracker != nullptr && tracker->tracker.status() ? 1 : 0;
}

kg_status kg_tracker_process(kg_tracker* tracker, const kg_image* image, kg_detection* out,
                             size_t capacity, size_t* count) {
  kg::ImageView frame;
  if (const kg_status s = kg::capi::frame_arguments(tracker, image, out, capacity, count,
                                                    "kg_tracker_process: NULL argument", frame);
      s != KG_OK)
    return s;
  if (kg::Status s = tracker->tracker.process(frame, tracker->found); !s) return fail(s);
  *count = kg::capi::copy_detections(*tracker->detector->index, tracker->found, out, capacity,
                                     tracker->caller_truncated);
  return KG_OK;
}

void kg_tracker_reset(kg_tracker* tracker) {
  if (tracker != nullptr) tracker->tracker.reset();
}

kg_status kg_tracker_stats(const kg_tracker* tracker, kg_tracking_stats* out) {
  if (tracker == nullptr || out == nullptr)
    return fail(KG_INVALID_ARGUMENT, "kg_tracker_stats: NULL argument");
  const kg::TrackerStats& s = tracker->tracker.stats();
  std::memset(out, 0, sizeof *out);
  out->tracks = s.tracks;
  out->confirmed = s.confirmed;
  out->lost = s.lost;
  out->detected = s.detected ? 1 : 0;
  out->ms_track = s.ms_track;
  out->ms_detect = s.ms_detect;
  out->frames = s.frames;
  out->detected_frames = s.detected_frames;
  return KG_OK;
}

}  // extern "C"
