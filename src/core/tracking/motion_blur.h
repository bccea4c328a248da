// The look of a model's appearance under motion blur: a camera moving
// during the exposure smears the object along its motion, and a sharp
// appearance then correlates poorly with it, at the right pose too. The
// tracker knows the motion (the corners' last step), so it can smear the
// appearance the same way and align that instead.
#pragma once

#include <cstdint>

namespace kg {

// Averages `src` (width x height, 8-bit, row-major) along the segment from
// -(dx, dy) / 2 to +(dx, dy) / 2 (pixels; at most 64 long) into `dst`,
// bilinear, the border replicated. `dst` must not alias `src`.
void blur_along(const std::uint8_t* src, int width, int height, float dx, float dy,
                std::uint8_t* dst);

}  // namespace kg
