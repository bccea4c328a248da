// Frame sources: where the detector's gray frames come from (a V4L2 device,
// a libcamera camera, or image files on a host). Every source hands out a
// non-owning kg::ImageView of 8-bit gray pixels; for camera formats whose
// first plane is luma (GREY, NV12, YU12) the view points straight into the
// capture buffer, so no pixel is copied.
//
// Life cycle, the same for every source:
//   start()  once: opens the device or file list and allocates every buffer
//            the source will ever use;
//   next()   per frame: returns the next frame; the frame (its pixels and
//            its view) stays valid until the next call to next() or stop();
//   stop()   releases everything; start() may be called again afterwards.
// A source is used from one thread (the caller's); camera sources move
// frames from their driver's thread to the caller internally.
//
// Errors are kg::Status values, never exceptions. next() distinguishes:
//   is_timeout(s)        no frame within timeout_ms; call next() again;
//   is_end_of_stream(s)  a finite source (files) has no more frames;
//   is_bad_frame(s)      this one frame was unusable (short buffer, driver
//                        error flag); the source keeps streaming, call
//                        next() again;
//   anything else        the source failed (device disconnected, I/O
//                        error); every later next() returns the same error
//                        until stop() and a successful start().
#pragma once

#include <cstdint>
#include <string>

#include "keygraph/image.h"
#include "keygraph/status.h"

namespace kg::platform {

struct Frame {
  ImageView image;                 // gray, 8 bits per pixel; not owned
  std::uint64_t timestamp_ns = 0;  // capture time on CLOCK_MONOTONIC, in nanoseconds
  std::uint64_t sequence = 0;      // frame counter from the source; gaps mean dropped frames
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;

  // Opens the source and allocates its buffers. Errors: missing device or
  // files, not a capture device, no supported pixel format, out of buffers.
  virtual Status start() = 0;

  // Waits up to timeout_ms (< 0: no limit; files never wait) for the next
  // frame and fills `out`. The previous frame becomes invalid here.
  virtual Status next(Frame& out, int timeout_ms) = 0;

  // Stops streaming and releases every buffer; safe to call twice and on a
  // source that failed or never started.
  virtual void stop() = 0;

  // One line for logs: device, negotiated format and size once started.
  virtual std::string description() const = 0;
};

// The status codes next() uses for the non-fatal outcomes listed above.
inline constexpr StatusCode kTimeoutCode = StatusCode::kTimeout;
inline constexpr StatusCode kEndOfStreamCode = StatusCode::kEndOfStream;
inline constexpr StatusCode kBadFrameCode = StatusCode::kBadFrame;

inline bool is_timeout(const Status& s) {
  return s.code() == kTimeoutCode;
}
inline bool is_end_of_stream(const Status& s) {
  return s.code() == kEndOfStreamCode;
}
inline bool is_bad_frame(const Status& s) {
  return s.code() == kBadFrameCode;
}

}  // namespace kg::platform
