// The largest image the file readers accept. Checked against the size a
// file's header declares, before pixel memory is allocated, so a small file
// that declares a huge image (a decompression bomb: 260 KB of PNG for
// 16384 x 16384 pixels) is refused instead of taking gigabytes.
#pragma once

#include <cstddef>

namespace kg::platform {

// Pixels (width * height): 16.7 million, e.g. 4096 x 4096 or a 12-megapixel
// photo; a side at most 32768 (PGM) or 16384 (the detector's limit).
inline constexpr long long kMaxImagePixels = 1LL << 24;
// The same as text, for the environment (checked below).
inline constexpr char kMaxImagePixelsText[] = "16777216";
// Bytes of a whole image file read into memory: room for 16-bit RGBA at
// the pixel limit, plus headers and metadata.
inline constexpr std::size_t kMaxImageFileBytes = (std::size_t{1} << 27) + (std::size_t{1} << 20);

namespace detail {
constexpr long long parse_decimal(const char* s, long long v = 0) {
  return *s == '\0' ? v : parse_decimal(s + 1, v * 10 + (*s - '0'));
}
}  // namespace detail
static_assert(detail::parse_decimal(kMaxImagePixelsText) == kMaxImagePixels);

// Sets OpenCV imgcodecs' OPENCV_IO_MAX_IMAGE_PIXELS to kMaxImagePixels (a
// lower value already in the environment is kept); imgcodecs then checks
// every image's declared size against it before allocating (tested for PNG
// and JPEG with OpenCV 4.6). OpenCV 4.6 reads the variable once, while
// libopencv_imgcodecs is loaded, before main(): measured, a 16384x16384
// PNG was still decoded with the variable set from main(). So it must be in
// the environment when the program starts: src/cli/main.cpp sets it and
// executes itself again.
void limit_image_decoders();

}  // namespace kg::platform
