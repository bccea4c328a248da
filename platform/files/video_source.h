// Frames from a video file (AVI, MP4, MKV, ...) through OpenCV videoio, for
// hosts: `keygraph live --video FILE`. Built only into a files library
// built with OpenCV when OpenCV's videoio is found (platform/CMakeLists.txt,
// KG_FILES_HAVE_VIDEO); OpenCV stays out of this header.
//
// start() refuses, with one message naming the file: a path that is not a
// regular file (regular_file.h: a FIFO, a directory, a device), a file
// videoio cannot open ("cannot open video FILE (...)"), and frames over the
// pixel limit of the image files (image_limits.h). Decoded frames (BGR,
// BGRA or gray) become 8-bit gray in a buffer the source keeps and reuses
// from frame to frame, with OpenCV's weights (0.299 R + 0.587 G + 0.114 B).
//
// next() ignores its timeout (decoding never waits for a camera). After the
// last frame it returns end of stream (is_end_of_stream), or with `loop`
// opens the file again and starts over (end of stream when a pass gave no
// frame at all). A frame over the pixel limit or not of 8-bit samples is an
// error that ends the stream. timestamp_ns is the monotonic time the frame
// was decoded (as for image files; position_ms() gives the container's
// position); sequence counts the frames delivered since start().
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "keygraph/platform/frame_source.h"

namespace kg::platform {

struct VideoSourceOptions {
  bool loop = false;  // open the file again after its last frame
};

class VideoSource final : public FrameSource {
 public:
  explicit VideoSource(std::string path, VideoSourceOptions options = {});
  ~VideoSource() override;
  VideoSource(const VideoSource&) = delete;
  VideoSource& operator=(const VideoSource&) = delete;

  // Errors: missing file (kNotFound), not a regular file or unreadable
  // (kIoError), not a video videoio opens (kCorruptData), frames over the
  // pixel limit (kResourceExhausted).
  Status start() override;
  Status next(Frame& out, int timeout_ms) override;
  void stop() override;
  std::string description() const override;

  const std::string& path() const { return path_; }
  // The container's position of the last frame next() delivered, in
  // milliseconds from the start of the file (0 before the first frame).
  double position_ms() const { return position_ms_; }

 private:
  struct Capture;  // cv::VideoCapture and the frame buffers

  Status open();

  std::string path_;
  VideoSourceOptions options_;
  std::unique_ptr<Capture> capture_;
  std::uint64_t sequence_ = 0;
  std::uint64_t in_pass_ = 0;  // frames delivered since the file was (re)opened
  double position_ms_ = 0;
  bool started_ = false;
};

}  // namespace kg::platform
