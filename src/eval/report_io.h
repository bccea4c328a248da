// Small helpers for the evaluation reports: JSON values, outputs written
// whole or not at all (platform/files/output_file.h, output_set.h), PNG
// output.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

#include "keygraph/status.h"
#include "platform/files/output_set.h"

namespace kg {

std::string json_quote(std::string_view s);
// Shortest round-trip-safe text; "null" for NaN and infinities.
std::string json_value(double v);

// Writes `text` to `path` whole or not at all (a unique temporary renamed
// into place), never over a non-regular file or one of `inputs`.
Status write_text_file(const std::string& path, const std::string& text,
                       const std::vector<std::string>& inputs = {});

// The PNG encoding of `image` (the error names `path`).
Status encode_png(const cv::Mat& image, const std::string& path, std::vector<std::uint8_t>& png);
// Stages `image` as a PNG in `out` (output_set.h).
Status add_png(platform::OutputSet& out, const std::string& path, const cv::Mat& image);

// The regular files in `dir` and its subdirectories down to `depth`
// levels (1: `dir` alone), links followed: a data set's files, which a
// report must not overwrite. Empty when `dir` is empty or not a directory.
std::vector<std::string> files_under(const std::string& dir, int depth);

}  // namespace kg
