// Paths of the real images the tests use, and a loader. A missing file is
// a test failure (ASSERT in the caller), never a skip; a test that needs a
// data set is not registered without it (KG_REQUIRE_DATA, data_dir.h).
#pragma once

#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "keygraph/image.h"
#include "support/data_dir.h"

namespace kg::test {

inline std::string opencv_data(const std::string& name) {
  return std::string(KG_OPENCV_DATA_DIR) + "/" + name;
}
inline std::string oxford(const std::string& subset, const std::string& name) {
  return data_dir("oxford") + "/" + subset + "/" + name;
}

// Loads an image as 8-bit gray; empty Mat when unreadable.
inline cv::Mat load_gray(const std::string& path) {
  return cv::imread(path, cv::IMREAD_GRAYSCALE);
}

inline ImageView view(const cv::Mat& m) {
  return ImageView(m.data, m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step));
}

}  // namespace kg::test
