// Small helpers for the evaluation reports: JSON values, files written
// through a temporary name and a rename, PNG output.
#pragma once

#include <string>
#include <string_view>

#include <opencv2/core.hpp>

#include "keygraph/status.h"

namespace kg {

std::string json_quote(std::string_view s);
// Shortest round-trip-safe text; "null" for NaN and infinities.
std::string json_value(double v);

// Writes `text` to `path` via `path.tmp` and a rename: never half-written.
Status write_text_file(const std::string& path, const std::string& text);
// The same for a PNG image.
Status write_png_file(const std::string& path, const cv::Mat& image);

// Creates the directory (and parents) if needed.
Status ensure_directory(const std::string& path);

}  // namespace kg
