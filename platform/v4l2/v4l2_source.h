// Frames from a Video4Linux2 capture device (/dev/videoN): memory-mapped
// streaming I/O, single- or multi-planar API, whichever the device offers.
//
// start() opens the device, picks the pixel format cheapest to turn into
// gray among those the device lists (GREY > NV12 > YU12 > YUYV > UYVY; the
// multi-planar NV12M and YUV420M count as NV12 and YU12), requests
// `buffer_count` buffers once, maps each once, queues them all and starts
// streaming. next() gives the previous frame's buffer back to the driver,
// waits with poll() and dequeues the next one: GREY, NV12 and YU12 frames are
// views of the mapped luma plane (no copy), YUYV and UYVY frames are
// converted into a buffer allocated by start(). Nothing is allocated per
// frame.
//
// Errors (see frame_source.h for the classes next() returns):
//   start(): missing path (kNotFound); not a character device, not a V4L2
//   capture device, no streaming, no supported format (kInvalidArgument);
//   permission, ioctl or mmap failures (kIoError).
//   next(): no frame within the timeout (is_timeout); a buffer with fewer
//   bytes than the negotiated frame or flagged as an error by the driver
//   (is_bad_frame; the buffer goes back to the driver); the device was
//   unplugged (ENODEV) or reported an error (kIoError, sticky until stop()).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "keygraph/platform/convert.h"
#include "keygraph/platform/frame_source.h"
#include "keygraph/platform/v4l2/system_io.h"

namespace kg::platform {

struct V4l2Options {
  std::string device = "/dev/video0";
  int width = 640;            // requested; the driver may pick the nearest size it supports
  int height = 480;           // requested
  unsigned buffer_count = 4;  // requested; the driver may grant more, or fewer (at least 2)
};

class V4l2Source final : public FrameSource {
 public:
  // `io` must outlive the source; tests pass a fake device.
  explicit V4l2Source(V4l2Options options, v4l2::SystemIo& io = v4l2::system_io());
  ~V4l2Source() override;
  V4l2Source(const V4l2Source&) = delete;
  V4l2Source& operator=(const V4l2Source&) = delete;

  Status start() override;
  Status next(Frame& out, int timeout_ms) override;
  void stop() override;
  std::string description() const override;

  // The negotiated frame layout (valid after a successful start()).
  const FrameLayout& layout() const { return layout_; }
  // Driver-granted buffer count (after start()).
  std::size_t buffer_count() const { return buffers_.size(); }

 private:
  struct Plane {
    void* addr = nullptr;
    std::size_t length = 0;
  };
  struct Buffer {
    Plane planes[3];
  };

  Status open_device();
  Status negotiate_format();
  Status allocate_buffers();
  Status queue_buffer(unsigned index);
  Status fail(Status status);  // records a sticky error and returns it
  Status dequeue(Frame& out, bool& again);
  std::string prefix() const;

  V4l2Options options_;
  v4l2::SystemIo& io_;
  int fd_ = -1;
  bool multiplanar_ = false;
  bool streaming_ = false;
  unsigned mem_planes_ = 1;  // memory planes per buffer (multi-planar API)
  std::uint32_t fourcc_ = 0;
  FrameLayout layout_;
  std::size_t expected_bytes_ = 0;  // minimum bytesused of plane 0
  std::vector<Buffer> buffers_;
  std::vector<std::uint8_t> gray_;  // YUYV/UYVY conversion target
  int held_ = -1;                   // index of the buffer behind the last frame
  Status error_;                    // sticky failure, reported by next()
};

}  // namespace kg::platform
