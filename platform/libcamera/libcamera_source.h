// Frames from a libcamera camera (Raspberry Pi and other ISP-based boards,
// UVC webcams through libcamera's uvcvideo pipeline). Written against the
// libcamera 0.0.3 API of Debian bookworm.
//
// start() takes the process-wide camera manager (one per process, shared by
// every LibcameraSource), acquires the camera, configures one viewfinder
// stream in the pixel format cheapest to turn into gray among those the
// camera offers (R8 > NV12 > YUV420 > YUYV > UYVY), allocates the buffers
// once (FrameBufferAllocator), maps each buffer once after checking every
// plane's offset and length against the size of its dmabuf, creates one
// request per buffer and queues them all. The completion callback runs on
// libcamera's thread and only appends the request to a queue (mutex +
// condition variable); next() takes it from there on the caller's thread,
// gives the previous frame's request back to the camera (reused, same
// buffer), and hands out a view of the mapped luma plane (R8, NV12, YUV420:
// no copy) or of a buffer it converted into (YUYV, UYVY).
//
// Errors: no camera, an unknown id, a camera in use, no supported format
// (start()); no frame within the timeout (is_timeout), a cancelled or failed
// frame or a short buffer (is_bad_frame, the request is requeued), the
// camera unplugged (kIoError, sticky until stop()).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "keygraph/platform/frame_source.h"

namespace kg::platform {

struct LibcameraOptions {
  std::string camera_id;  // empty: the first camera the manager lists
  int width = 640;        // requested; the pipeline may adjust it
  int height = 480;
  unsigned buffer_count = 4;  // requested; the pipeline may adjust it
};

// The ids of the cameras libcamera sees, in the manager's order. Errors: the
// camera manager fails to start (kIoError).
Status list_libcamera_cameras(std::vector<std::string>& ids);

class LibcameraSource final : public FrameSource {
 public:
  explicit LibcameraSource(LibcameraOptions options);
  ~LibcameraSource() override;
  LibcameraSource(const LibcameraSource&) = delete;
  LibcameraSource& operator=(const LibcameraSource&) = delete;

  Status start() override;
  Status next(Frame& out, int timeout_ms) override;
  void stop() override;
  std::string description() const override;

 private:
  struct State;  // libcamera objects, kept out of this header
  LibcameraOptions options_;
  std::unique_ptr<State> state_;
};

}  // namespace kg::platform
