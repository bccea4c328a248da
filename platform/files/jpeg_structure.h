// Whether a JPEG file is complete. libjpeg decodes a truncated JPEG with
// only a warning ("Premature end of JPEG file") and grey fill for the
// missing part, which OpenCV passes on as a valid image. This walks the
// file's marker segments (skipping each by its length, so thumbnails inside
// APP1 do not count) and the entropy-coded data of each scan (where 0xFF is
// always followed by 0x00 or a restart marker) up to the end-of-image
// marker; data after it (e.g. a motion photo's video) is allowed.
#pragma once

#include <cstddef>
#include <cstdint>

namespace kg::platform {

// True when `data` starts with a JPEG's start-of-image marker.
bool is_jpeg(const std::uint8_t* data, std::size_t size);

// For a JPEG (is_jpeg): true when its end-of-image marker is reached
// through its segments and scans, false when the data ends before it.
bool jpeg_is_complete(const std::uint8_t* data, std::size_t size);

}  // namespace kg::platform
