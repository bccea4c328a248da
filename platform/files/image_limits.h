// The largest image the file readers accept. Checked against the size a
// file's header declares, before pixel memory is allocated (PGM: pgm.h;
// every other format: image_header.h, before OpenCV decodes), so a small
// file that declares a huge image (a decompression bomb: 260 KB of PNG for
// 16384 x 16384 pixels) is refused instead of taking gigabytes, in any
// process, with no environment to set.
#pragma once

#include <cstddef>

namespace kg::platform {

// Pixels (width * height): 16.7 million, e.g. 4096 x 4096 or a 12-megapixel
// photo; a side at most 32768 (PGM) or 16384 (the detector's limit).
inline constexpr long long kMaxImagePixels = 1LL << 24;
// Bytes of a whole image file read into memory: room for 16-bit RGBA at
// the pixel limit, plus headers and metadata.
inline constexpr std::size_t kMaxImageFileBytes = (std::size_t{1} << 27) + (std::size_t{1} << 20);

}  // namespace kg::platform
