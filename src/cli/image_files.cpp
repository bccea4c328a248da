// Image files for the desktop commands, through OpenCV (builder/image_io.h).
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "builder/image_io.h"
#include "cli/commands.h"
#include "platform/files/file_source.h"
#include "platform/files/held_stderr.h"
#include "platform/files/image_header.h"
#include "platform/files/image_limits.h"
#include "platform/files/jpeg_structure.h"
#include "platform/files/output_file.h"
#include "platform/files/pgm.h"

namespace kg::cli {

namespace {

// The factor by which cv::IMREAD_* `flags` divide each side.
int reduction_of(int flags) {
  switch (flags) {
    case cv::IMREAD_REDUCED_GRAYSCALE_2:
    case cv::IMREAD_REDUCED_COLOR_2:
      return 2;
    case cv::IMREAD_REDUCED_GRAYSCALE_4:
    case cv::IMREAD_REDUCED_COLOR_4:
      return 4;
    case cv::IMREAD_REDUCED_GRAYSCALE_8:
    case cv::IMREAD_REDUCED_COLOR_8:
      return 8;
    default:
      return 1;
  }
}

// Decodes `path` with `flags` (cv::IMREAD_*) under the checks of
// load_gray(): a regular file, checked before decoding, within the pixel
// limit at the size decoded (the header's size, platform/files/
// image_header.h, reduced as `flags` ask). `bytes` is the file.
Status decode(const std::string& path, const std::vector<std::uint8_t>& bytes, int flags,
              cv::Mat& out) {
  out.release();
  if (Status s = platform::check_declared_size(bytes, path, reduction_of(flags)); !s) return s;
  platform::StderrHold decoder_messages;
  decoder_messages.hold();
  bool over_limit = false;
  try {
    const cv::Mat raw(1, static_cast<int>(bytes.size()), CV_8U,
                      const_cast<std::uint8_t*>(bytes.data()));
    out = cv::imdecode(raw, flags);
  } catch (const cv::Exception& e) {
    out.release();
    over_limit = platform::is_size_limit_error(e.err);
  }
  decoder_messages.release(!out.empty());
  if (over_limit) return {StatusCode::kResourceExhausted, platform::over_pixel_limit(path)};
  if (out.empty()) return {StatusCode::kInvalidArgument, path + ": not a readable image"};
  return Status::ok();
}

Status read_checked(const std::string& path, std::vector<std::uint8_t>& bytes) {
  if (Status s = platform::read_file(path, bytes); !s) return s;
  if (const std::string problem = platform::problem_before_decoding(bytes, path); !problem.empty())
    return {StatusCode::kCorruptData, problem};
  return Status::ok();
}

}  // namespace

Status load_image(const std::string& path, cv::Mat& gray) {
  // Decoders' complaints are held: on failure our one line replaces them,
  // on success they are passed on (e.g. libpng's sRGB profile warnings).
  platform::StderrHold decoder_messages;
  decoder_messages.hold();
  Status s = load_gray(path, gray);
  decoder_messages.release(s.is_ok());
  return s;
}

Status load_color(const std::string& path, cv::Mat& bgr) {
  std::vector<std::uint8_t> bytes;
  if (Status s = read_checked(path, bytes); !s) return s;
  return decode(path, bytes, cv::IMREAD_COLOR, bgr);
}

Status load_model_photo(const std::string& path, cv::Mat& gray, int& scale) {
  scale = 1;
  Status s = load_image(path, gray);
  if (s.code() != StatusCode::kResourceExhausted) return s;
  std::vector<std::uint8_t> bytes;
  if (Status r = read_checked(path, bytes); !r) return r;
  if (!platform::is_jpeg(bytes.data(), bytes.size())) {
    return {s.code(), s.message() + "; --max-side downsamples JPEG files only: make this one " +
                          "smaller, or save it as JPEG"};
  }
  const std::pair<int, int> reduced[] = {{2, cv::IMREAD_REDUCED_GRAYSCALE_2},
                                         {4, cv::IMREAD_REDUCED_GRAYSCALE_4},
                                         {8, cv::IMREAD_REDUCED_GRAYSCALE_8}};
  for (const auto& [factor, flags] : reduced) {
    s = decode(path, bytes, flags, gray);
    if (s.code() == StatusCode::kResourceExhausted) continue;
    if (s) scale = factor;
    return s;
  }
  return {s.code(), s.message() + " (also at 1/8 of its size)"};
}

bool write_image_atomically(const std::string& path, const cv::Mat& image,
                            const std::vector<std::string>& inputs, std::string& error) {
  std::string ext = std::filesystem::path(path).extension().string();
  if (ext.empty()) {
    error = path + ": output image needs an extension such as .png";
    return false;
  }
  // The temporary keeps the extension: the encoder is chosen from it.
  platform::OutputFile out;
  Status s = out.create(path, inputs, ext);
  if (s) s = out.close();
  if (s) {
    // The encoder's own complaint (on several lines) is held: our one line
    // replaces it.
    platform::StderrHold encoder_messages;
    encoder_messages.hold();
    bool written = false;
    try {
      written = cv::imwrite(out.temp_path(), image);
    } catch (const cv::Exception&) {
      written = false;
    }
    encoder_messages.release(written);
    if (!written)
      s = {StatusCode::kIoError,
           "cannot write image " + path + " (OpenCV cannot write this picture as " + ext + ")"};
  }
  if (s) s = out.commit();
  if (!s) error = s.message();
  return s.is_ok();
}

}  // namespace kg::cli
