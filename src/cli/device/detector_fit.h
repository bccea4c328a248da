// Detectors sized for the frames a command sees.
#pragma once

#include "keygraph/detector.h"

namespace kg::cli {

// Rebuilds `detector` with room for `frame` when the frame is larger than
// its limits (the workspace is allocated again: once per new largest size,
// never for frames that fit). Returns the detector's status.
inline const Status& fit_detector(Detector& detector, ImageView frame) {
  const Limits& limits = detector.limits();
  if (frame.width > limits.max_width || frame.height > limits.max_height) {
    detector = Detector(
        detector.index(),
        limits.for_frame(frame.width > limits.max_width ? frame.width : limits.max_width,
                         frame.height > limits.max_height ? frame.height : limits.max_height));
  }
  return detector.status();
}

}  // namespace kg::cli
