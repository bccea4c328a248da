#include "platform/files/file_source.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <utility>

#include "platform/convert.h"
#include "platform/files/held_stderr.h"
#include "platform/files/image_header.h"
#include "platform/files/image_limits.h"
#include "platform/files/jpeg_structure.h"

#if KG_PLATFORM_FILES_OPENCV
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#endif

namespace kg::platform {
namespace fs = std::filesystem;

namespace {

bool has_image_extension(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  static const char* const kExtensions[] = {".pgm", ".png",  ".jpg", ".jpeg", ".bmp",
                                            ".tif", ".tiff", ".ppm", ".pnm",  ".webp"};
  for (const char* e : kExtensions) {
    if (ext == e) return true;
  }
  return false;
}

std::uint64_t monotonic_ns() {
  // steady_clock is CLOCK_MONOTONIC on Linux.
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::steady_clock::now().time_since_epoch())
                                        .count());
}

#if KG_PLATFORM_FILES_OPENCV
Status decode_with_opencv(std::vector<std::uint8_t>& bytes, const std::string& path, cv::Mat& gray,
                          StderrHold& decoder_messages) {
  if (const std::string problem = problem_before_decoding(bytes, path); !problem.empty())
    return {kBadFrameCode, "files: " + problem};
  // The pixel limit, from the header (image_header.h).
  if (Status s = check_declared_size(bytes, path); !s)
    return {kBadFrameCode, "files: " + s.message()};
  // imdecode reports most problems with an empty result; some throw, among
  // them an image over OpenCV's own limit (OPENCV_IO_MAX_IMAGE_PIXELS).
  bool too_large = false;
  decoder_messages.hold();
  try {
    const cv::Mat raw(1, static_cast<int>(bytes.size()), CV_8U, bytes.data());
    gray = cv::imdecode(raw, cv::IMREAD_GRAYSCALE);
  } catch (const cv::Exception& e) {
    too_large = is_size_limit_error(e.err);
    gray.release();
  }
  const bool ok = !gray.empty() && gray.type() == CV_8UC1;
  decoder_messages.release(ok);
  if (too_large) return {kBadFrameCode, "files: " + over_pixel_limit(path)};
  if (!gray.empty() && !ok) {
    return {kBadFrameCode, "files: " + not_8bit_gray(path, gray.channels(), gray.depth())};
  }
  if (!ok) return {kBadFrameCode, "files: " + path + ": not an image OpenCV can decode"};
  return Status::ok();
}
#else
Status not_decodable(const std::string& path) {
  return {kBadFrameCode, "files: " + path +
                             ": not a binary PGM (P5); this build has no OpenCV imgcodecs, so it "
                             "reads PGM files only"};
}
#endif

}  // namespace

struct FileSource::Decoded {
#if KG_PLATFORM_FILES_OPENCV
  cv::Mat gray;
  StderrHold decoder_messages;
#endif
};

bool is_size_limit_error(const std::string& opencv_error) {
  // The assertion in imgcodecs' validateInputImageSize() names the limit.
  return opencv_error.find("CV_IO_MAX_IMAGE") != std::string::npos;
}

std::string over_pixel_limit(const std::string& path) {
  return path + ": image over " + std::to_string(kMaxImagePixels) +
         " pixels (the limit), not decoded";
}

std::string not_8bit_gray(const std::string& path, int channels, int opencv_depth) {
  static const char* const kDepths[] = {"8-bit",         "8-bit signed",   "16-bit",
                                        "16-bit signed", "32-bit integer", "32-bit float",
                                        "64-bit float",  "16-bit float"};
  const char* depth = opencv_depth >= 0 && opencv_depth < 8 ? kDepths[opencv_depth] : "unknown";
  return path + ": decodes to " + std::to_string(channels) + " channel(s) of " + depth +
         " values, not 8-bit gray (a Radiance HDR, say): convert it to PNG or JPEG";
}

std::string problem_before_decoding(const std::vector<std::uint8_t>& bytes,
                                    const std::string& path) {
  if (bytes.empty()) return path + ": empty file";
  if (is_jpeg(bytes.data(), bytes.size()) && !jpeg_is_complete(bytes.data(), bytes.size()))
    return path + ": truncated JPEG (the data ends before the end-of-image marker)";
  return {};
}

bool file_source_uses_opencv() {
  return KG_PLATFORM_FILES_OPENCV != 0;
}

Status read_image(const std::string& path, GrayImage& out) {
  std::vector<std::uint8_t> bytes;
  if (Status s = read_file(path, bytes); !s) return {s.code(), "files: " + s.message()};
  if (is_pgm(bytes.data(), bytes.size())) {
    if (Status s = decode_pgm(bytes.data(), bytes.size(), path, out); !s) {
      return {StatusCode::kCorruptData, "files: " + s.message()};
    }
    return Status::ok();
  }
#if KG_PLATFORM_FILES_OPENCV
  cv::Mat gray;
  StderrHold decoder_messages;
  if (Status s = decode_with_opencv(bytes, path, gray, decoder_messages); !s) {
    return {StatusCode::kCorruptData, s.message()};
  }
  out.width = gray.cols;
  out.height = gray.rows;
  out.pixels.resize(static_cast<std::size_t>(gray.cols) * static_cast<std::size_t>(gray.rows));
  copy_gray(ImageView(gray.data, gray.cols, gray.rows, static_cast<std::ptrdiff_t>(gray.step)),
            out.pixels.data(), gray.cols);
  return Status::ok();
#else
  return {StatusCode::kCorruptData, not_decodable(path).message()};
#endif
}

Status list_image_files(const std::string& dir, std::vector<std::string>& out) {
  out.clear();
  std::error_code ec;
  const fs::file_status st = fs::status(dir, ec);
  if (st.type() == fs::file_type::not_found) {
    return {StatusCode::kNotFound, "files: " + dir + ": no such directory"};
  }
  if (ec) return {StatusCode::kIoError, "files: " + dir + ": " + ec.message()};
  if (!fs::is_directory(st)) return {StatusCode::kIoError, "files: " + dir + ": not a directory"};
  fs::directory_iterator it(dir, ec);
  if (ec) return {StatusCode::kIoError, "files: " + dir + ": cannot list: " + ec.message()};
  for (; it != fs::directory_iterator(); it.increment(ec)) {
    if (ec) break;
    std::error_code ec2;
    if (it->is_regular_file(ec2) && has_image_extension(it->path())) {
      out.push_back(it->path().string());
    }
  }
  if (ec) return {StatusCode::kIoError, "files: " + dir + ": cannot list: " + ec.message()};
  std::sort(out.begin(), out.end());
  return Status::ok();
}

FileSource::FileSource(std::vector<std::string> paths, FileSourceOptions options)
    : paths_(std::move(paths)), options_(options), decoded_(std::make_unique<Decoded>()) {}

FileSource::~FileSource() = default;

Status FileSource::start() {
  stop();
  std::vector<std::string> files;
  for (const std::string& p : paths_) {
    std::error_code ec;
    const fs::file_status st = fs::status(p, ec);
    if (st.type() == fs::file_type::not_found) {
      return {StatusCode::kNotFound, "files: " + p + ": no such file or directory"};
    }
    if (ec) return {StatusCode::kIoError, "files: " + p + ": " + ec.message()};
    if (fs::is_directory(st)) {
      std::vector<std::string> listed;
      if (Status s = list_image_files(p, listed); !s) return s;
      files.insert(files.end(), listed.begin(), listed.end());
    } else {
      files.push_back(p);
    }
  }
  if (files.empty()) {
    std::string where;
    for (const std::string& p : paths_) where += (where.empty() ? "" : ", ") + p;
    return {StatusCode::kNotFound,
            "files: no image files in " + (where.empty() ? std::string("(no paths)") : where)};
  }
  files_ = std::move(files);
  position_ = 0;
  sequence_ = 0;
  started_ = true;
  return Status::ok();
}

Status FileSource::decode(const std::string& path, Frame& out) {
  if (Status s = read_file(path, bytes_); !s) {
    return {kBadFrameCode, "files: " + s.message()};
  }
  if (is_pgm(bytes_.data(), bytes_.size())) {
    if (Status s = decode_pgm(bytes_.data(), bytes_.size(), path, gray_); !s) {
      return {kBadFrameCode, "files: " + s.message()};
    }
    out.image = gray_.view();
    return Status::ok();
  }
#if KG_PLATFORM_FILES_OPENCV
  if (Status s = decode_with_opencv(bytes_, path, decoded_->gray, decoded_->decoder_messages); !s)
    return s;
  const cv::Mat& g = decoded_->gray;
  out.image = ImageView(g.data, g.cols, g.rows, static_cast<std::ptrdiff_t>(g.step));
  return Status::ok();
#else
  return not_decodable(path);
#endif
}

Status FileSource::next(Frame& out, int /*timeout_ms*/) {
  if (!started_) return {StatusCode::kInvalidArgument, "files: next() before start()"};
  if (position_ >= files_.size()) {
    if (!options_.loop) {
      return {kEndOfStreamCode,
              "files: end of stream after " + std::to_string(files_.size()) + " files"};
    }
    position_ = 0;
  }
  last_path_ = files_[position_++];
  if (Status s = decode(last_path_, out); !s) return s;
  out.timestamp_ns = monotonic_ns();
  out.sequence = sequence_++;
  return Status::ok();
}

void FileSource::stop() {
  started_ = false;
  files_.clear();
  position_ = 0;
  last_path_.clear();
  bytes_ = {};
  gray_ = {};
#if KG_PLATFORM_FILES_OPENCV
  decoded_->gray.release();
#endif
}

std::string FileSource::description() const {
  std::string d = "files";
  for (const std::string& p : paths_) d += " " + p;
  if (started_) d += ": " + std::to_string(files_.size()) + " images";
  d += file_source_uses_opencv() ? " (decoders: PGM, OpenCV imgcodecs)" : " (decoder: PGM only)";
  return d;
}

}  // namespace kg::platform
