// 2x bilinear upsampling of a frame (KeypointParams::scene_upsample), and
// the map between its pixels and the frame's.
#pragma once

#include <cstdint>

#include "core/image/plane.h"
#include "keygraph/image.h"
#include "keygraph/types.h"

namespace kg {

// Pixel centres follow image.h: frame pixel x lies at upsampled
// 2 x + 0.5 (OpenCV's resize convention), so the two grids share the
// frame's outer edge.
inline float to_upsampled(float v) {
  return 2.f * v + 0.5f;
}
inline float from_upsampled(float v) {
  return 0.5f * (v - 0.5f);
}

// dst becomes 2 src.width x 2 src.height: each output pixel is 9/16, 3/16,
// 3/16, 1/16 of its four nearest source pixels (borders replicated),
// rounded. dst must be reserved for that size (no allocation then).
void upsample2x(ImageView src, Plane<std::uint8_t>& dst);

// H maps model pixels to upsampled pixels; the result maps them to frame
// pixels (the scaling above applied after H).
Homography homography_from_upsampled(const Homography& h);
// The inverse: H maps model pixels to frame pixels; the result maps them
// to upsampled pixels.
Homography homography_to_upsampled(const Homography& h);

}  // namespace kg
