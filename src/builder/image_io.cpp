#include "builder/image_io.h"

#include <cstdint>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "platform/files/file_source.h"
#include "platform/files/image_header.h"
#include "platform/files/image_limits.h"
#include "platform/files/pgm.h"

namespace kg {

Status load_gray(const std::string& path, cv::Mat& out) {
  out.release();
  // The file's bytes first (a regular file only, never a blocking open),
  // checked before a decoder sees them: complete, and within the pixel
  // limit by the size its header declares.
  std::vector<std::uint8_t> bytes;
  if (Status s = platform::read_file(path, bytes); !s) return s;
  if (const std::string problem = platform::problem_before_decoding(bytes, path); !problem.empty())
    return {StatusCode::kCorruptData, problem};
  if (Status s = platform::check_declared_size(bytes, path); !s) return s;
  try {
    const cv::Mat raw(1, static_cast<int>(bytes.size()), CV_8U, bytes.data());
    out = cv::imdecode(raw, cv::IMREAD_GRAYSCALE);
  } catch (const cv::Exception& e) {
    out.release();
    if (platform::is_size_limit_error(e.err))
      return {StatusCode::kResourceExhausted, platform::over_pixel_limit(path)};
  }
  if (out.empty()) return {StatusCode::kInvalidArgument, path + ": not a readable image"};
  if (out.type() != CV_8UC1) {
    const int channels = out.channels(), depth = out.depth();
    out.release();
    return {StatusCode::kInvalidArgument, platform::not_8bit_gray(path, channels, depth)};
  }
  if (out.cols < 16 || out.rows < 16)
    return {StatusCode::kInvalidArgument, path + ": image too small (" + std::to_string(out.cols) +
                                              "x" + std::to_string(out.rows) + ")"};
  if (out.cols > 16384 || out.rows > 16384 ||
      static_cast<long long>(out.cols) * out.rows > platform::kMaxImagePixels) {
    const std::string size = std::to_string(out.cols) + "x" + std::to_string(out.rows);
    out.release();
    return {StatusCode::kInvalidArgument, path + ": image too large (" + size + ")"};
  }
  return Status::ok();
}

}  // namespace kg
