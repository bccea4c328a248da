// Image files for the desktop tools (OpenCV imgcodecs).
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "keygraph/image.h"
#include "keygraph/status.h"

namespace kg {

// Loads `path` as 8-bit gray. Errors: missing file, unreadable or empty image.
Status load_gray(const std::string& path, cv::Mat& out);

inline ImageView view_of(const cv::Mat& gray) {
  return ImageView(gray.data, gray.cols, gray.rows, static_cast<std::ptrdiff_t>(gray.step));
}

}  // namespace kg
