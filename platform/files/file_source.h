// Frames from image files, for hosts and for replaying recordings on a
// device: a list of paths, each a file or a directory. A directory stands for
// its image files (regular files named *.pgm, *.png, *.jpg, *.jpeg, *.bmp,
// *.tif, *.tiff, *.ppm, *.pnm, *.webp; case-insensitive), sorted by name in
// byte order (number frames with leading zeros: frame_0009, frame_0010).
//
// Decoders: binary PGM (P5) always, with no dependency; every other format
// through OpenCV imgcodecs when the library was built with it
// (file_source_uses_opencv()), converted to gray by OpenCV. Without OpenCV
// such a file is a bad frame with a message saying so.
//
// next() ignores its timeout: reading a file never waits for a camera. A
// file that cannot be read or decoded is reported as a bad frame
// (is_bad_frame) and skipped, so the next call reads the next file. After
// the last file next() returns end of stream (is_end_of_stream), or starts
// over when `loop` is set. timestamp_ns is the monotonic time the file was
// read; sequence counts the frames delivered since start().
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "keygraph/platform/files/pgm.h"
#include "keygraph/platform/frame_source.h"

namespace kg::platform {

struct FileSourceOptions {
  bool loop = false;  // restart at the first file after the last one
};

// True when this build decodes non-PGM images with OpenCV imgcodecs.
bool file_source_uses_opencv();

// Reads one image file into `out` with the decoders described above (its
// capacity is reused). Errors: missing file (kNotFound), unreadable
// (kIoError), not an image this build decodes (kCorruptData); each message
// names the file.
Status read_image(const std::string& path, GrayImage& out);

// Checks on a file's bytes before a decoder sees them: empty, or a JPEG
// that ends before its end-of-image marker (jpeg_structure.h). Returns the
// error message (naming `path`), or empty.
std::string problem_before_decoding(const std::vector<std::uint8_t>& bytes,
                                    const std::string& path);
// Whether an OpenCV exception's text is imgcodecs refusing an image over its
// own size limits (OPENCV_IO_MAX_IMAGE_PIXELS; keygraph's limit,
// image_limits.h, is checked before that: image_header.h), and the message
// for it.
bool is_size_limit_error(const std::string& opencv_error);
std::string over_pixel_limit(const std::string& path);
// The message for a file a decoder turns into something other than 8-bit
// gray (OpenCV decodes a Radiance HDR to 3 channels of float even when
// asked for gray): `channels` of OpenCV's element depth `opencv_depth`
// (CV_8U 0 ... CV_64F 6, CV_16F 7).
std::string not_8bit_gray(const std::string& path, int channels, int opencv_depth);

// The image files of `dir` as described above, sorted. Errors: missing
// directory (kNotFound), not a directory or unreadable (kIoError).
Status list_image_files(const std::string& dir, std::vector<std::string>& out);

class FileSource final : public FrameSource {
 public:
  explicit FileSource(std::vector<std::string> paths, FileSourceOptions options = {});
  ~FileSource() override;
  FileSource(const FileSource&) = delete;
  FileSource& operator=(const FileSource&) = delete;

  // Expands directories and checks that every path exists. Errors: a
  // missing path (kNotFound), a directory that cannot be listed (kIoError),
  // no image file at all (kNotFound).
  Status start() override;
  Status next(Frame& out, int timeout_ms) override;
  void stop() override;
  std::string description() const override;

  // The files in reading order (after start()).
  const std::vector<std::string>& files() const { return files_; }
  // The file the last next() read, also when it was a bad frame; empty
  // before the first next() and after stop().
  const std::string& last_path() const { return last_path_; }

 private:
  struct Decoded;  // OpenCV image, when built with OpenCV

  Status decode(const std::string& path, Frame& out);

  std::vector<std::string> paths_;
  FileSourceOptions options_;
  std::vector<std::string> files_;
  std::size_t position_ = 0;
  std::string last_path_;
  std::uint64_t sequence_ = 0;
  bool started_ = false;
  std::vector<std::uint8_t> bytes_;   // the current file's contents, reused
  GrayImage gray_;                    // PGM pixels, reused
  std::unique_ptr<Decoded> decoded_;  // OpenCV pixels, reused
};

}  // namespace kg::platform
