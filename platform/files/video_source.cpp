#include "platform/files/video_source.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <utility>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <opencv2/videoio/registry.hpp>

#include "platform/files/held_stderr.h"
#include "platform/files/image_limits.h"
#include "platform/files/regular_file.h"

namespace kg::platform {

namespace {

std::uint64_t monotonic_ns() {
  // steady_clock is CLOCK_MONOTONIC on Linux.
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::steady_clock::now().time_since_epoch())
                                        .count());
}

std::string size_text(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

bool beyond_pixel_limit(long long width, long long height) {
  return width * height > kMaxImagePixels;
}

std::string over_limit_message(const std::string& path, int width, int height) {
  return "video " + path + ": frames of " + size_text(width, height) + ", over " +
         std::to_string(kMaxImagePixels) + " pixels (the limit), not decoded";
}

}  // namespace

struct VideoSource::Capture {
  cv::VideoCapture video;
  cv::Mat decoded;  // the frame as videoio gives it (BGR), reused
  cv::Mat gray;     // its gray version, reused
  // Gray = 0.114 B + 0.587 G + 0.299 R (OpenCV's BT.601 weights); BGRA
  // ignores alpha. cv::transform is in opencv_core: the platform layer does
  // not link imgproc (cmake/KeygraphLayers.cmake).
  const cv::Matx13f bgr_weights{0.114f, 0.587f, 0.299f};
  const cv::Matx14f bgra_weights{0.114f, 0.587f, 0.299f, 0.0f};
  StderrHold decoder_messages;
  int width = 0, height = 0;
  double fps = 0;
  long long frame_count = 0;
};

VideoSource::VideoSource(std::string path, VideoSourceOptions options)
    : path_(std::move(path)), options_(options), capture_(std::make_unique<Capture>()) {}

VideoSource::~VideoSource() = default;

Status VideoSource::open() {
  Capture& c = *capture_;
  // FFmpeg when this OpenCV has it: CAP_ANY would also hand the name to
  // GStreamer (which reads "a ! b" as a pipeline) or to the image-sequence
  // reader ("frame_%03d.png").
  const int backend =
      cv::videoio_registry::hasBackend(cv::CAP_FFMPEG) ? cv::CAP_FFMPEG : cv::CAP_ANY;
  // Decoders print their complaints on stderr: the one error line below
  // replaces them when the file does not open.
  c.decoder_messages.hold();
  bool opened = false;
  try {
    opened = c.video.open(path_, backend);
  } catch (const cv::Exception&) {
    opened = false;
  }
  c.decoder_messages.release(opened);
  if (!opened) {
    c.video.release();
    return {StatusCode::kCorruptData,
            "cannot open video " + path_ +
                " (not a video format or codec this build's OpenCV videoio decodes)"};
  }
  return Status::ok();
}

Status VideoSource::start() {
  stop();
  // A FIFO would block the decoder's open() for ever, a directory or a
  // device would be read as garbage: only regular files.
  int fd = -1;
  struct stat info {};
  if (Status s = open_regular_file(path_, fd, info); !s) return {s.code(), "video " + s.message()};
  ::close(fd);
  if (Status s = open(); !s) return s;
  Capture& c = *capture_;
  c.width = static_cast<int>(c.video.get(cv::CAP_PROP_FRAME_WIDTH));
  c.height = static_cast<int>(c.video.get(cv::CAP_PROP_FRAME_HEIGHT));
  c.fps = c.video.get(cv::CAP_PROP_FPS);
  c.frame_count = static_cast<long long>(c.video.get(cv::CAP_PROP_FRAME_COUNT));
  if (beyond_pixel_limit(c.width, c.height)) {
    const Status s{StatusCode::kResourceExhausted, over_limit_message(path_, c.width, c.height)};
    stop();
    return s;
  }
  sequence_ = 0;
  in_pass_ = 0;
  position_ms_ = 0;
  started_ = true;
  return Status::ok();
}

Status VideoSource::next(Frame& out, int /*timeout_ms*/) {
  if (!started_) return {StatusCode::kInvalidArgument, "video: next() before start()"};
  Capture& c = *capture_;
  bool got = false;
  try {
    got = c.video.read(c.decoded);
    if (!got && options_.loop && in_pass_ > 0) {
      // Reopening is what works for every container (seeking to frame 0
      // is not exact in all of them).
      if (Status s = open(); !s) return s;
      in_pass_ = 0;
      got = c.video.read(c.decoded);
    }
  } catch (const cv::Exception& e) {
    return {StatusCode::kIoError, "video " + path_ + ": decoding failed: " + e.err};
  }
  if (!got || c.decoded.empty()) {
    return {kEndOfStreamCode,
            "video: end of stream after " + std::to_string(sequence_) + " frames"};
  }
  const cv::Mat& d = c.decoded;
  if (beyond_pixel_limit(d.cols, d.rows))
    return {StatusCode::kResourceExhausted, over_limit_message(path_, d.cols, d.rows)};
  if (d.depth() != CV_8U || (d.channels() != 1 && d.channels() != 3 && d.channels() != 4)) {
    return {StatusCode::kCorruptData, "video " + path_ + ": decodes to " +
                                          std::to_string(d.channels()) +
                                          " channel(s) of other than 8-bit samples"};
  }
  const cv::Mat* gray = &d;
  if (d.channels() == 3) {
    cv::transform(d, c.gray, c.bgr_weights);
    gray = &c.gray;
  } else if (d.channels() == 4) {
    cv::transform(d, c.gray, c.bgra_weights);
    gray = &c.gray;
  }
  out.image =
      ImageView(gray->data, gray->cols, gray->rows, static_cast<std::ptrdiff_t>(gray->step));
  out.timestamp_ns = monotonic_ns();
  out.sequence = sequence_++;
  ++in_pass_;
  position_ms_ = c.video.get(cv::CAP_PROP_POS_MSEC);
  return Status::ok();
}

void VideoSource::stop() {
  started_ = false;
  Capture& c = *capture_;
  c.video.release();
  c.decoded.release();
  c.gray.release();
  c.width = c.height = 0;
  c.fps = 0;
  c.frame_count = 0;
}

std::string VideoSource::description() const {
  std::string d = "video " + path_;
  const Capture& c = *capture_;
  if (started_) {
    char rate[32];
    std::snprintf(rate, sizeof(rate), "%.3g fps", c.fps);
    d += ": " + size_text(c.width, c.height) + ", " + rate;
    if (c.frame_count > 0) d += ", " + std::to_string(c.frame_count) + " frames";
    d += " (OpenCV videoio, " + c.video.getBackendName() + ")";
  } else {
    d += " (OpenCV videoio)";
  }
  if (options_.loop) d += ", looping";
  return d;
}

}  // namespace kg::platform
