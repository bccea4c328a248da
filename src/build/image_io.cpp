#include "build/image_io.h"

#include <filesystem>
#include <system_error>

#include <opencv2/imgcodecs.hpp>

namespace kg {

Status load_gray(const std::string& path, cv::Mat& out) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    return {StatusCode::kNotFound, path + ": no such file"};
  try {
    out = cv::imread(path, cv::IMREAD_GRAYSCALE);
  } catch (const cv::Exception&) {
    out.release();
  }
  if (out.empty()) return {StatusCode::kInvalidArgument, path + ": not a readable image"};
  if (out.cols < 16 || out.rows < 16)
    return {StatusCode::kInvalidArgument, path + ": image too small (" + std::to_string(out.cols) +
                                              "x" + std::to_string(out.rows) + ")"};
  if (out.cols > 16384 || out.rows > 16384)
    return {StatusCode::kInvalidArgument, path + ": image too large"};
  return Status::ok();
}

}  // namespace kg
