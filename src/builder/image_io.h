// Image files for the desktop tools (OpenCV imgcodecs).
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "keygraph/image.h"
#include "keygraph/status.h"

namespace kg {

// Loads `path` as 8-bit gray: a regular file (platform/files/regular_file.h)
// of at most platform::kMaxImagePixels pixels (the size its header declares
// is checked before decoding: platform/files/image_header.h, an error
// kResourceExhausted), not a truncated JPEG. Errors: missing file, not a regular file (saying what
// it is), unreadable, truncated, too small or too large an image.
Status load_gray(const std::string& path, cv::Mat& out);

inline ImageView view_of(const cv::Mat& gray) {
  return ImageView(gray.data, gray.cols, gray.rows, static_cast<std::ptrdiff_t>(gray.step));
}

}  // namespace kg
