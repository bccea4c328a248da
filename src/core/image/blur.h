// Separable Gaussian blur. Kernel radius ceil(3 sigma), borders replicated.
#pragma once

#include <cstdint>

#include "core/image/plane.h"
#include "keygraph/image.h"

namespace kg {

// Kernel radius for sigma: ceil(3 sigma), at most 512. Scratch planes hold
// rows of width + 2 * radius floats: two rows for the 8-bit blur, one for
// the float one.
int blur_radius(float sigma);

// 8-bit in, 8-bit out (rounded). sigma <= 0 copies the image.
void gaussian_blur(ImageView src, float sigma, Plane<std::uint8_t>& dst, Plane<float>& scratch);

// Float in, float out. `dst` may not alias `src`.
void gaussian_blur(const Plane<float>& src, float sigma, Plane<float>& dst, Plane<float>& scratch);

// Rows [y0, y1) of the float blur, the same values as gaussian_blur()'s:
// threads split one blur into row bands, each with its own `scratch` (one
// row of width + 2 * radius floats). `dst` must already have src's size.
void gaussian_blur_rows(const Plane<float>& src, float sigma, Plane<float>& dst, int y0, int y1,
                        Plane<float>& scratch);

}  // namespace kg
