// The image size a file declares in its header, read before any decoder
// runs, so that the pixel limit (image_limits.h) holds in every process
// that decodes images (the keygraph tool, keygraph.build in Python, any
// program linking the file source), for every decoder call, reduced JPEG
// decoding included: a small file that declares a huge image (a
// decompression bomb) is refused without decoding.
//
// Read: PNG, JPEG, BMP, TIFF and BigTIFF, WebP, PNM (PBM, PGM, PPM, PAM,
// PFM) and Sun raster, the formats OpenCV 4.6's imgcodecs decodes whose
// size a header states; refused: JPEG 2000, OpenEXR and Radiance HDR, which
// imgcodecs would decode but whose size is not read here. Anything else is
// left to the decoder (which refuses what it does not know).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "keygraph/status.h"

namespace kg::platform {

struct DeclaredSize {
  enum Kind {
    kNotAnImage,  // no format above: the decoder decides
    kUnreadable,  // a format above, but its header ends or is malformed before the size
    kKnown,       // width x height as the header declares them
    kUnchecked,   // a format whose size is not read here (refused)
  };
  Kind kind = kNotAnImage;
  const char* format = "";  // "PNG", "JPEG", ... (static text)
  std::uint64_t width = 0;
  std::uint64_t height = 0;
};

DeclaredSize declared_image_size(const std::uint8_t* data, std::size_t size);

// The check before decoding `bytes` (the file at `path`), whose decoder
// divides each side by `reduction` (1; 2, 4 or 8 for OpenCV's reduced JPEG
// decoding): kResourceExhausted, "PATH: FORMAT of WxH pixels is over N
// pixels (the limit), not decoded", when the decoded image would be over
// kMaxImagePixels; kInvalidArgument for the formats refused above; ok
// otherwise (including headers it cannot read: the decoder refuses those).
Status check_declared_size(const std::vector<std::uint8_t>& bytes, const std::string& path,
                           int reduction = 1);

}  // namespace kg::platform
