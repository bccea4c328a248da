// Detectors sized for the frames a command sees.
#pragma once

#include <string>
#include <utility>

#include "keygraph/detector.h"
#include "platform/files/frame_limits.h"

namespace kg::cli {

// Rebuilds `detector` with room for `frame` when the frame does not fit
// its limits (platform::limits_for_frame(): the workspace is allocated
// again, once per frame that does not fit, never for frames that do, and
// never for the product of two thin frames' sides), with the same options
// (--set) and thread count. When the frame cannot
// be detected on (platform::frame_size_problem(), or no memory for the
// workspace), returns why and leaves `detector` as it was, so the caller
// can skip the frame.
inline Status fit_detector(Detector& detector, ImageView frame) {
  if (const std::string problem = platform::frame_size_problem(frame.width, frame.height);
      !problem.empty())
    return {StatusCode::kInvalidArgument, problem};
  const Limits& limits = detector.limits();
  if (frame.width <= limits.max_width && frame.height <= limits.max_height)
    return detector.status();
  Detector larger(detector.index(), platform::limits_for_frame(limits, frame.width, frame.height),
                  detector.options());
  if (!larger.status()) {
    return {larger.status().code(),
            "frame " + std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                " is beyond the detector's limits (" + larger.status().message() + ")"};
  }
  detector = std::move(larger);
  return detector.status();
}

}  // namespace kg::cli
