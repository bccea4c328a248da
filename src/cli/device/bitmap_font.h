// Text in gray pictures without OpenCV: the names that `live --draw` and the
// device build's `detect --draw` write beside each outline, as the desktop
// detect's OpenCV pictures do. A fixed 5 x 7 pixel font of printable ASCII
// (other bytes draw as a box), scaled by whole pixels.
#pragma once

#include <cstdint>
#include <string_view>

#include "platform/files/pgm.h"

namespace kg::cli {

constexpr int kGlyphWidth = 5, kGlyphHeight = 7;
constexpr int kGlyphAdvance = kGlyphWidth + 1;  // one column between letters

// The width in pixels of `text` drawn at `scale`; its height is
// kGlyphHeight * scale, all above the baseline.
int text_width(std::string_view text, int scale);

// Draws `text` with its bottom-left corner at (x, baseline) in `value`, with
// a one-pixel edge in `edge` around each letter so it reads on any
// background. Clipped to the picture: any position is safe.
void draw_text(platform::GrayImage& img, std::string_view text, int x, int baseline, int scale,
               std::uint8_t value, std::uint8_t edge);

}  // namespace kg::cli
