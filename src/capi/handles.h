// What the C API's opaque handles hold (include/keygraph/keygraph.h), and
// the helpers its entry points share. The C API wraps the public C++
// contract (keygraph/) and nothing else.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "keygraph/detector.h"
#include "keygraph/keygraph.h"
#include "keygraph/model_index.h"
#include "keygraph/status.h"
#include "keygraph/tracker.h"

// An index and the NUL-terminated copies of its model names (the C++
// ModelInfo::name is a string_view into the file, not terminated), made
// once when the index is opened.
struct kg_index {
  kg::ModelIndex index;
  std::unique_ptr<char[]> name_bytes;
  std::unique_ptr<const char*[]> names;  // model_count() pointers into name_bytes
};

// A detector, the list its frames fill (kept here rather than on the
// caller's stack: 64 detections are about 13 KB), and the model selection,
// which Detector::options() does not return and set_option() re-applies.
struct kg_detector {
  kg_detector(const kg_index& owner, const kg::Limits& limits)
      : index(&owner), detector(owner.index, limits) {}
  kg_detector(const kg_index& owner, const kg::Limits& limits, void* buffer, std::size_t size)
      : index(&owner), detector(owner.index, limits, buffer, size) {}
  const kg_index* index;
  kg::Detector detector;
  kg::DetectionList found;
  std::vector<std::int32_t> models;  // empty: every model
  bool caller_truncated = false;     // the last frame found more than the caller's capacity
};

// A tracker over a detector handle, with the list its frames fill.
struct kg_tracker {
  kg_tracker(kg_detector& owner, const kg::TrackerOptions& options)
      : detector(&owner), tracker(owner.detector, options) {}
  kg_detector* detector;
  kg::Tracker tracker;
  kg::DetectionList found;
  bool caller_truncated = false;
};

namespace kg::capi {

// Copies the first `capacity` of `found` into `out` (names from `index`)
// and returns how many; `truncated` says whether some did not fit.
std::size_t copy_detections(const kg_index& index, const DetectionList& found, kg_detection* out,
                            std::size_t capacity, bool& truncated);
// The argument checks of kg_detect() and kg_tracker_process() (`handle` is
// theirs; `null_message` static text naming the function): `*count` set to
// 0, then KG_OK and the frame's view, or the error recorded.
kg_status frame_arguments(const void* handle, const kg_image* image, const kg_detection* out,
                          std::size_t capacity, std::size_t* count, const char* null_message,
                          ImageView& view);

// Records `status`'s message as this thread's last error (kg_last_error())
// and returns its code.
kg_status fail(const Status& status);
// The same for a message of the C API's own (static text).
kg_status fail(kg_status code, const char* message);

}  // namespace kg::capi
