// Detector limits for frames of any size, one after the other (image files,
// desktop scenes): grown for a frame that does not fit, never to the
// product of the largest width and the largest height seen. A 16 x 16384
// frame then a 16384 x 16 one would otherwise ask for a 16384 x 16384
// workspace (6 GB); here the second gets one of its own shape instead.
#pragma once

#include <algorithm>
#include <string>

#include "keygraph/detector.h"
#include "platform/files/image_limits.h"

namespace kg::platform {

// The smallest frame side the tools take (as `keygraph detect` does).
inline constexpr int kMinFrameSide = 16;

// `current` when the frame fits it; otherwise limits holding both the frame
// and `current`'s frames when that is at most kMaxImagePixels, else the
// frame's own size (at least the default Limits a side: a frame of up to
// kMaxImagePixels gets at most that much). Counts are kept from `current`.
inline Limits limits_for_frame(const Limits& current, int width, int height) {
  if (width <= current.max_width && height <= current.max_height) return current;
  const int w = std::max(width, current.max_width), h = std::max(height, current.max_height);
  if (static_cast<long long>(w) * h <= kMaxImagePixels) return current.for_frame(w, h);
  const Limits defaults;
  return current.for_frame(std::max(width, defaults.max_width),
                           std::max(height, defaults.max_height));
}

// Why a frame cannot be detected on at all (empty when it can): over
// Limits::kMaxSide or under kMinFrameSide pixels a side.
inline std::string frame_size_problem(int width, int height) {
  const std::string size = std::to_string(width) + "x" + std::to_string(height);
  if (width > Limits::kMaxSide || height > Limits::kMaxSide)
    return "frame " + size + " is beyond the detector's limits (" +
           std::to_string(Limits::kMaxSide) + " pixels a side)";
  if (width < kMinFrameSide || height < kMinFrameSide)
    return "frame " + size + " is too small (under " + std::to_string(kMinFrameSide) +
           " pixels a side)";
  return {};
}

}  // namespace kg::platform
