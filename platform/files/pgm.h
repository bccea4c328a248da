// Binary PGM (P5) without any dependency, so device builds can read and
// write image files too. Spec: netpbm's pgm(5): "P5", whitespace, width,
// height, maxval (1..65535) as ASCII decimals with '#' comments allowed
// between them, exactly one whitespace byte, then width * height samples of
// one byte (maxval < 256) or two big-endian bytes (maxval >= 256).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "keygraph/image.h"
#include "keygraph/status.h"

namespace kg::platform {

// An 8-bit gray image that owns its pixels, rows packed (stride == width).
struct GrayImage {
  std::vector<std::uint8_t> pixels;
  int width = 0;
  int height = 0;

  ImageView view() const { return ImageView(pixels.data(), width, height, width); }
};

// True when `data` starts with the P5 magic.
bool is_pgm(const std::uint8_t* data, std::size_t size);

// Decodes a P5 image held in memory; samples are scaled to 0..255 when
// maxval != 255 (16-bit samples by rounding v * 255 / maxval). `out` reuses
// its capacity. `name` only labels error messages. Errors (kCorruptData):
// wrong magic (with a hint for ASCII P2 and color P6), malformed or
// out-of-range header fields, images over 32768 pixels a side or over
// kMaxImagePixels (image_limits.h; checked before `out` grows), truncated
// pixel data.
Status decode_pgm(const std::uint8_t* data, std::size_t size, const std::string& name,
                  GrayImage& out);

// Reads a whole image file into `bytes` (capacity reused): a regular file
// of at most kMaxImageFileBytes (regular_file.h). Errors: missing file
// (kNotFound), unreadable or not a regular file (kIoError, saying what it
// is), too large (kResourceExhausted).
Status read_file(const std::string& path, std::vector<std::uint8_t>& bytes);

// read_file + decode_pgm.
Status read_pgm(const std::string& path, GrayImage& out);

// Writes `image` as an 8-bit P5 file through an OutputFile
// (output_file.h): whole or not at all, never over a non-regular file or
// one of `inputs`.
Status write_pgm(const std::string& path, const ImageView& image,
                 const std::vector<std::string>& inputs = {});

}  // namespace kg::platform
