// Detectors sized for the frames a command sees.
#pragma once

#include <string>
#include <utility>

#include "keygraph/detector.h"

namespace kg::cli {

// Rebuilds `detector` with room for `frame` when the frame is larger than
// its limits (the workspace is allocated again: once per new largest size,
// never for frames that fit). When the frame is beyond what a detector can
// take (over 16384 pixels a side, or no memory for the workspace), returns
// why and leaves `detector` as it was, so the caller can skip the frame.
inline Status fit_detector(Detector& detector, ImageView frame) {
  const Limits& limits = detector.limits();
  if (frame.width <= limits.max_width && frame.height <= limits.max_height)
    return detector.status();
  Detector larger(
      detector.index(),
      limits.for_frame(frame.width > limits.max_width ? frame.width : limits.max_width,
                       frame.height > limits.max_height ? frame.height : limits.max_height));
  if (!larger.status()) {
    return {larger.status().code(),
            "frame " + std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                " is beyond the detector's limits (" + larger.status().message() + ")"};
  }
  detector = std::move(larger);
  return detector.status();
}

}  // namespace kg::cli
