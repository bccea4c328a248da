// The V4L2 source: against a real capture device when the machine has one
// (skipped with "no camera device: not run" otherwise), against paths that
// are not capture devices, and against a simulated driver (FakeDevice, a
// SystemIo) that checks the streaming protocol: format preference, buffers
// requested and mapped once and recycled, zero-copy luma views, YUYV
// conversion, short buffers, driver error flags, timeouts, a device that
// disappears, multi-planar NV12M.
#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "camera_checks.h"
#include "platform/v4l2/v4l2_source.h"

namespace kg::platform {
namespace {
namespace fs = std::filesystem;

// ------------------------------------------------------------ real devices

std::vector<std::string> video_devices() {
  std::vector<std::string> out;
  std::error_code ec;
  for (fs::directory_iterator it("/dev", ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind("video", 0) == 0) out.push_back(it->path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(V4l2Device, CapturesFramesFromARealCamera) {
  const std::vector<std::string> devices = video_devices();
  if (devices.empty()) GTEST_SKIP() << "no camera device: not run (no /dev/video* on this machine)";
  std::string tried;
  for (const std::string& dev : devices) {
    V4l2Source src(V4l2Options{dev, 640, 480, 4});
    const Status s = src.start();
    if (!s) {
      tried += "\n  " + s.message();
      continue;  // e.g. a metadata node beside the capture node
    }
    std::printf("%s\n", src.description().c_str());
    test::expect_ordered_frames(src, 10, src.layout().width, src.layout().height);
    src.stop();
    return;
  }
  GTEST_SKIP() << "no camera device: not run (no capture device among /dev/video*:" << tried << ")";
}

TEST(V4l2Device, NotAVideoDeviceIsOneClearError) {
  V4l2Source src(V4l2Options{"/dev/null"});
  const Status s = src.start();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  // The errno text is the kernel's (ENOTTY: "Inappropriate ioctl for device";
  // qemu-user, which does not emulate V4L2 ioctls, gives ENOSYS).
  EXPECT_EQ(s.message().rfind("v4l2: /dev/null: not a V4L2 device (VIDIOC_QUERYCAP: ", 0), 0u)
      << s.message();
  Frame f;
  EXPECT_EQ(src.next(f, 10).code(), StatusCode::kInvalidArgument);  // not started: no crash
  src.stop();
  src.stop();
}

TEST(V4l2Device, MissingPathIsNotFound) {
  V4l2Source src(V4l2Options{"/dev/video-keygraph-missing"});
  const Status s = src.start();
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_EQ(s.message(),
            "v4l2: /dev/video-keygraph-missing: no such device (No such file or directory)");
}

TEST(V4l2Device, RegularFileIsNotADevice) {
  const std::string path = std::string(KG_TEST_OUTPUT_DIR) + "/not_a_camera.bin";
  std::ofstream(path) << "frame";
  V4l2Source src(V4l2Options{path});
  const Status s = src.start();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("not a character device"), std::string::npos) << s.message();
  std::remove(path.c_str());
}

// ------------------------------------------------------- simulated driver

// A capture device in memory. Pixels of frame n: luma(x, y) + n.
class FakeDevice final : public v4l2::SystemIo {
 public:
  static constexpr int kFd = 42;
  std::vector<std::uint32_t> formats = {V4L2_PIX_FMT_YUYV};
  bool multiplanar = false;
  int width = 64, height = 48;
  int padding = 0;       // extra bytes per row
  unsigned grant = 0;    // buffers granted by REQBUFS (0: as many as asked)
  bool stalled = false;  // poll() times out
  bool disconnected = false;
  std::map<std::uint32_t, std::uint32_t> short_frames;  // sequence -> bytesused
  std::vector<std::uint32_t> error_frames;              // sequences flagged V4L2_BUF_FLAG_ERROR

  // Counters the tests check.
  int opens = 0, closes = 0, reqbufs = 0, mmaps = 0, munmaps = 0, qbufs = 0, dqbufs = 0;
  int streamons = 0, streamoffs = 0;

  static std::uint8_t luma(int x, int y, std::uint32_t n) {
    return static_cast<std::uint8_t>((x * 5 + y * 9 + static_cast<int>(n)) & 0xff);
  }

  int open(const char* path, int) override {
    if (std::string(path) != "/dev/fake0") return errno = ENOENT, -1;
    ++opens;
    return kFd;
  }
  int close(int fd) override {
    EXPECT_EQ(fd, kFd);
    ++closes;
    return 0;
  }
  int fstat(int, struct stat* st) override {
    *st = {};
    st->st_mode = S_IFCHR | 0660;
    return 0;
  }
  int poll(struct pollfd* fds, nfds_t, int) override {
    if (disconnected) return fds->revents = POLLERR | POLLHUP, 1;
    if (stalled || !streaming_ || queued_.empty()) return fds->revents = 0, 0;
    fds->revents = POLLIN;
    return 1;
  }
  void* mmap(std::size_t length, int, int, int fd, off_t offset) override {
    EXPECT_EQ(fd, kFd);
    const std::size_t key = static_cast<std::size_t>(offset);
    if (memory_.count(key) == 0 || memory_[key].size() != length) return errno = EINVAL, MAP_FAILED;
    ++mmaps;
    mapped_.push_back(memory_[key].data());
    return memory_[key].data();
  }
  int munmap(void* addr, std::size_t) override {
    auto it = std::find(mapped_.begin(), mapped_.end(), addr);
    EXPECT_NE(it, mapped_.end());
    if (it != mapped_.end()) mapped_.erase(it);
    ++munmaps;
    return 0;
  }
  bool owns(const std::uint8_t* p) const {
    for (const auto& [offset, mem] : memory_) {
      if (p >= mem.data() && p < mem.data() + mem.size()) return true;
    }
    return false;
  }
  std::size_t still_mapped() const { return mapped_.size(); }

  int ioctl(int fd, unsigned long request, void* arg) override {
    EXPECT_EQ(fd, kFd);
    if (disconnected && request != VIDIOC_STREAMOFF && request != VIDIOC_REQBUFS) {
      return errno = ENODEV, -1;
    }
    const std::uint32_t type =
        multiplanar ? V4L2_BUF_TYPE_VIDEO_CAPTURE_MPLANE : V4L2_BUF_TYPE_VIDEO_CAPTURE;
    switch (request) {
      case VIDIOC_QUERYCAP: {
        auto* cap = static_cast<v4l2_capability*>(arg);
        *cap = {};
        std::snprintf(reinterpret_cast<char*>(cap->driver), sizeof cap->driver, "fake");
        cap->device_caps = V4L2_CAP_STREAMING |
                           (multiplanar ? V4L2_CAP_VIDEO_CAPTURE_MPLANE : V4L2_CAP_VIDEO_CAPTURE);
        cap->capabilities = cap->device_caps | V4L2_CAP_DEVICE_CAPS;
        return 0;
      }
      case VIDIOC_ENUM_FMT: {
        auto* d = static_cast<v4l2_fmtdesc*>(arg);
        if (d->type != type || d->index >= formats.size()) return errno = EINVAL, -1;
        d->pixelformat = formats[d->index];
        d->flags = formats[d->index] == V4L2_PIX_FMT_MJPEG ? V4L2_FMT_FLAG_COMPRESSED : 0;
        return 0;
      }
      case VIDIOC_S_FMT: {
        auto* f = static_cast<v4l2_format*>(arg);
        if (f->type != type) return errno = EINVAL, -1;
        const std::uint32_t want = multiplanar ? f->fmt.pix_mp.pixelformat : f->fmt.pix.pixelformat;
        // Like drivers do: an unknown format is replaced, not refused.
        fourcc_ =
            std::find(formats.begin(), formats.end(), want) != formats.end() ? want : formats[0];
        const bool packed = fourcc_ == V4L2_PIX_FMT_YUYV || fourcc_ == V4L2_PIX_FMT_UYVY;
        bpl_ = static_cast<std::uint32_t>((packed ? 2 * width : width) + padding);
        const std::uint32_t luma_size = bpl_ * static_cast<std::uint32_t>(height);
        if (multiplanar) {
          auto& p = f->fmt.pix_mp;
          p.pixelformat = fourcc_;
          p.width = static_cast<std::uint32_t>(width);
          p.height = static_cast<std::uint32_t>(height);
          p.num_planes = fourcc_ == V4L2_PIX_FMT_NV12M ? 2 : 1;
          p.plane_fmt[0].bytesperline = bpl_;
          p.plane_fmt[0].sizeimage = p.num_planes == 2 ? luma_size : luma_size * 3 / 2;
          p.plane_fmt[1].bytesperline = bpl_;
          p.plane_fmt[1].sizeimage = luma_size / 2;
          planes_ = p.num_planes;
          sizes_[0] = p.plane_fmt[0].sizeimage;
          sizes_[1] = p.plane_fmt[1].sizeimage;
        } else {
          auto& p = f->fmt.pix;
          p.pixelformat = fourcc_;
          p.width = static_cast<std::uint32_t>(width);
          p.height = static_cast<std::uint32_t>(height);
          p.bytesperline = bpl_;
          p.sizeimage = packed || fourcc_ == V4L2_PIX_FMT_GREY ? luma_size : luma_size * 3 / 2;
          planes_ = 1;
          sizes_[0] = p.sizeimage;
        }
        return 0;
      }
      case VIDIOC_REQBUFS: {
        auto* r = static_cast<v4l2_requestbuffers*>(arg);
        EXPECT_EQ(r->type, type);
        EXPECT_EQ(r->memory, static_cast<std::uint32_t>(V4L2_MEMORY_MMAP));
        ++reqbufs;
        if (r->count == 0) {
          EXPECT_EQ(still_mapped(), 0u) << "REQBUFS(0) with buffers still mapped";
          memory_.clear();
          count_ = 0;
          return 0;
        }
        if (grant != 0) r->count = grant;
        count_ = r->count;
        for (std::uint32_t i = 0; i < count_; ++i) {
          for (std::uint32_t p = 0; p < planes_; ++p) memory_[offset(i, p)].assign(sizes_[p], 0);
        }
        return 0;
      }
      case VIDIOC_QUERYBUF: {
        auto* b = static_cast<v4l2_buffer*>(arg);
        if (b->index >= count_) return errno = EINVAL, -1;
        if (multiplanar) {
          for (std::uint32_t p = 0; p < planes_; ++p) {
            b->m.planes[p].length = sizes_[p];
            b->m.planes[p].m.mem_offset = static_cast<std::uint32_t>(offset(b->index, p));
          }
          b->length = planes_;
        } else {
          b->length = sizes_[0];
          b->m.offset = static_cast<std::uint32_t>(offset(b->index, 0));
        }
        return 0;
      }
      case VIDIOC_QBUF: {
        auto* b = static_cast<v4l2_buffer*>(arg);
        if (b->index >= count_ ||
            std::find(queued_.begin(), queued_.end(), b->index) != queued_.end()) {
          return errno = EINVAL, -1;
        }
        ++qbufs;
        queued_.push_back(b->index);
        return 0;
      }
      case VIDIOC_DQBUF: {
        auto* b = static_cast<v4l2_buffer*>(arg);
        if (!streaming_ || queued_.empty()) return errno = EAGAIN, -1;
        ++dqbufs;
        const std::uint32_t index = queued_.front();
        queued_.pop_front();
        const std::uint32_t seq = sequence_++;
        fill(index, seq);
        std::uint32_t used = sizes_[0];
        if (short_frames.count(seq)) used = short_frames[seq];
        b->index = index;
        b->sequence = seq;
        b->flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
        if (std::find(error_frames.begin(), error_frames.end(), seq) != error_frames.end()) {
          b->flags |= V4L2_BUF_FLAG_ERROR;
        }
        b->timestamp.tv_sec = 100 + seq;
        b->timestamp.tv_usec = 250;
        if (multiplanar) {
          b->m.planes[0].bytesused = used;
          b->m.planes[0].data_offset = 0;
          if (planes_ > 1) b->m.planes[1].bytesused = sizes_[1];
        } else {
          b->bytesused = used;
        }
        return 0;
      }
      case VIDIOC_STREAMON:
        ++streamons;
        streaming_ = true;
        return 0;
      case VIDIOC_STREAMOFF:
        ++streamoffs;
        streaming_ = false;
        queued_.clear();
        return 0;
      default:
        return errno = ENOTTY, -1;
    }
  }

 private:
  static std::size_t offset(std::uint32_t index, std::uint32_t plane) {
    return (static_cast<std::size_t>(index) * 4 + plane) * 0x100000;
  }
  void fill(std::uint32_t index, std::uint32_t seq) {
    std::vector<std::uint8_t>& mem = memory_[offset(index, 0)];
    std::fill(mem.begin(), mem.end(), 0xEE);
    const bool yuyv = fourcc_ == V4L2_PIX_FMT_YUYV, uyvy = fourcc_ == V4L2_PIX_FMT_UYVY;
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        const std::size_t row = static_cast<std::size_t>(y) * bpl_;
        if (yuyv || uyvy) {
          mem[row + 2 * x + (uyvy ? 1 : 0)] = luma(x, y, seq);
          mem[row + 2 * x + (uyvy ? 0 : 1)] = 128;
        } else {
          mem[row + x] = luma(x, y, seq);
        }
      }
    }
  }

  std::uint32_t fourcc_ = 0, bpl_ = 0, planes_ = 1, count_ = 0, sequence_ = 0;
  std::uint32_t sizes_[2] = {0, 0};
  bool streaming_ = false;
  std::map<std::size_t, std::vector<std::uint8_t>> memory_;
  std::vector<void*> mapped_;
  std::deque<std::uint32_t> queued_;
};

void expect_frame(const Frame& f, int w, int h, std::uint32_t seq) {
  ASSERT_EQ(f.image.width, w);
  ASSERT_EQ(f.image.height, h);
  EXPECT_EQ(f.sequence, seq);
  EXPECT_EQ(f.timestamp_ns, (100u + seq) * 1000000000ull + 250000u);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      ASSERT_EQ(f.image.at(x, y), FakeDevice::luma(x, y, seq)) << x << "," << y << " seq " << seq;
    }
  }
}

TEST(V4l2Fake, YuyvIsConvertedIntoOneBufferAndBuffersAreRecycled) {
  FakeDevice dev;
  dev.width = 33;  // odd width
  dev.height = 7;
  dev.padding = 6;
  V4l2Source src(V4l2Options{"/dev/fake0", 33, 7, 4}, dev);
  ASSERT_TRUE(src.start());
  EXPECT_EQ(src.layout().format, PixelFormat::kYuyv);
  EXPECT_EQ(src.layout().stride, 2 * 33 + 6);
  EXPECT_EQ(src.buffer_count(), 4u);
  EXPECT_NE(src.description().find("YUYV 33x7"), std::string::npos) << src.description();
  Frame f;
  const std::uint8_t* gray = nullptr;
  for (std::uint32_t i = 0; i < 20; ++i) {
    const Status s = src.next(f, 100);
    ASSERT_TRUE(s) << s.message();
    expect_frame(f, 33, 7, i);
    EXPECT_FALSE(dev.owns(f.image.data));  // converted, not a view of the driver buffer
    if (gray == nullptr) gray = f.image.data;
    EXPECT_EQ(f.image.data, gray);  // always the same preallocated buffer
  }
  EXPECT_EQ(dev.reqbufs, 1);     // requested once
  EXPECT_EQ(dev.mmaps, 4);       // mapped once each
  EXPECT_EQ(dev.qbufs, 4 + 19);  // every frame but the one held goes back
  src.stop();
  EXPECT_EQ(dev.reqbufs, 2);  // REQBUFS(0) after unmapping
  EXPECT_EQ(dev.munmaps, 4);
  EXPECT_EQ(dev.still_mapped(), 0u);
  EXPECT_EQ(dev.closes, 1);
  EXPECT_EQ(dev.streamoffs, 1);
}

TEST(V4l2Fake, PrefersTheCheapestFormatAndViewsTheLumaPlane) {
  struct Case {
    std::vector<std::uint32_t> offered;
    PixelFormat expected;
  };
  const Case cases[] = {
      {{V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_NV12}, PixelFormat::kNv12},
      {{V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_YUV420, V4L2_PIX_FMT_NV12, V4L2_PIX_FMT_GREY},
       PixelFormat::kGrey},
      {{V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_UYVY, V4L2_PIX_FMT_YUV420}, PixelFormat::kYu12},
      {{V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_UYVY}, PixelFormat::kUyvy},
  };
  for (const Case& c : cases) {
    FakeDevice dev;
    dev.formats = c.offered;
    dev.padding = 3;
    V4l2Source src(V4l2Options{"/dev/fake0", 64, 48, 3}, dev);
    ASSERT_TRUE(src.start());
    EXPECT_EQ(src.layout().format, c.expected) << pixel_format_name(c.expected);
    Frame f;
    for (std::uint32_t i = 0; i < 5; ++i) {
      ASSERT_TRUE(src.next(f, 100));
      expect_frame(f, 64, 48, i);
      EXPECT_EQ(dev.owns(f.image.data), is_zero_copy(c.expected));
    }
  }
}

TEST(V4l2Fake, MultiplanarNv12mIsZeroCopy) {
  FakeDevice dev;
  dev.multiplanar = true;
  dev.formats = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_NV12M};
  V4l2Source src(V4l2Options{"/dev/fake0", 64, 48, 4}, dev);
  ASSERT_TRUE(src.start());
  EXPECT_NE(src.description().find("NM12 64x48"), std::string::npos) << src.description();  // NV12M
  EXPECT_NE(src.description().find("multi-planar"), std::string::npos);
  EXPECT_EQ(dev.mmaps, 8);  // two planes per buffer
  Frame f;
  for (std::uint32_t i = 0; i < 6; ++i) {
    ASSERT_TRUE(src.next(f, 100));
    expect_frame(f, 64, 48, i);
    EXPECT_TRUE(dev.owns(f.image.data));
  }
  src.stop();
  EXPECT_EQ(dev.still_mapped(), 0u);
}

TEST(V4l2Fake, ShortBufferIsABadFrameAndStreamingGoesOn) {
  FakeDevice dev;
  dev.formats = {V4L2_PIX_FMT_NV12};
  dev.short_frames[2] = 1000;  // of 64 * 48 * 3 / 2 = 4608
  V4l2Source src(V4l2Options{"/dev/fake0", 64, 48, 4}, dev);
  ASSERT_TRUE(src.start());
  Frame f;
  ASSERT_TRUE(src.next(f, 100));
  ASSERT_TRUE(src.next(f, 100));
  const Status s = src.next(f, 100);
  EXPECT_TRUE(is_bad_frame(s)) << s.message();
  EXPECT_EQ(s.message(),
            "v4l2: /dev/fake0: short buffer: frame 2 has 1000 of 4608 bytes (NV12 64x48)");
  for (std::uint32_t seq = 3; seq < 10; ++seq) {
    ASSERT_TRUE(src.next(f, 100));
    expect_frame(f, 64, 48, seq);
  }
}

TEST(V4l2Fake, DriverErrorFlagIsABadFrame) {
  FakeDevice dev;
  dev.error_frames = {0};
  V4l2Source src(V4l2Options{"/dev/fake0", 64, 48, 2}, dev);
  ASSERT_TRUE(src.start());
  Frame f;
  const Status s = src.next(f, 100);
  EXPECT_TRUE(is_bad_frame(s));
  EXPECT_NE(s.message().find("frame 0 flagged as corrupt"), std::string::npos) << s.message();
  ASSERT_TRUE(src.next(f, 100));
  expect_frame(f, 64, 48, 1);
}

TEST(V4l2Fake, StalledStreamTimesOut) {
  FakeDevice dev;
  V4l2Source src(V4l2Options{"/dev/fake0", 64, 48, 2}, dev);
  ASSERT_TRUE(src.start());
  Frame f;
  ASSERT_TRUE(src.next(f, 100));
  dev.stalled = true;
  const Status s = src.next(f, 50);
  EXPECT_TRUE(is_timeout(s));
  EXPECT_EQ(s.message(), "v4l2: /dev/fake0: no frame within 50 ms");
  dev.stalled = false;  // a timeout is not fatal
  ASSERT_TRUE(src.next(f, 50));
  expect_frame(f, 64, 48, 1);
}

TEST(V4l2Fake, UnpluggedDeviceIsStickyAndCleansUp) {
  FakeDevice dev;
  V4l2Source src(V4l2Options{"/dev/fake0", 64, 48, 4}, dev);
  ASSERT_TRUE(src.start());
  Frame f;
  ASSERT_TRUE(src.next(f, 100));
  dev.disconnected = true;
  const Status s = src.next(f, 100);
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_EQ(s.message(), "v4l2: /dev/fake0: device disconnected (ENODEV)");
  EXPECT_FALSE(is_timeout(s) || is_bad_frame(s) || is_end_of_stream(s));
  EXPECT_EQ(src.next(f, 100).message(), s.message());  // sticky, no hang
  src.stop();
  EXPECT_EQ(dev.still_mapped(), 0u);
  EXPECT_EQ(dev.closes, 1);
}

TEST(V4l2Fake, UnpluggedWhileWaitingIsReportedByPoll) {
  FakeDevice dev;
  V4l2Source src(V4l2Options{"/dev/fake0", 64, 48, 4}, dev);
  ASSERT_TRUE(src.start());
  dev.disconnected = true;  // before any frame: poll says POLLERR, DQBUF says ENODEV
  Frame f;
  const Status s = src.next(f, 100);
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find("disconnected"), std::string::npos) << s.message();
}

TEST(V4l2Fake, UnsupportedFormatsAreListed) {
  FakeDevice dev;
  dev.formats = {V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_H264};
  V4l2Source src(V4l2Options{"/dev/fake0"}, dev);
  const Status s = src.start();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(s.message(),
            "v4l2: /dev/fake0: no supported pixel format: the device offers MJPG, H264; keygraph "
            "reads GREY, NV12, YU12, YUYV or UYVY");
  EXPECT_EQ(dev.closes, dev.opens);
}

TEST(V4l2Fake, TooFewBuffersIsAClearError) {
  FakeDevice dev;
  dev.grant = 1;
  V4l2Source src(V4l2Options{"/dev/fake0"}, dev);
  const Status s = src.start();
  EXPECT_EQ(s.code(), StatusCode::kResourceExhausted);
  EXPECT_NE(s.message().find("granted 1 buffer(s); streaming needs at least 2"), std::string::npos)
      << s.message();
  EXPECT_EQ(dev.still_mapped(), 0u);
  EXPECT_EQ(dev.closes, 1);
}

TEST(V4l2Fake, RestartAfterStop) {
  FakeDevice dev;
  V4l2Source src(V4l2Options{"/dev/fake0", 64, 48, 3}, dev);
  Frame f;
  for (int round = 0; round < 2; ++round) {
    ASSERT_TRUE(src.start());
    ASSERT_TRUE(src.next(f, 100));
    src.stop();
  }
  EXPECT_EQ(dev.opens, 2);
  EXPECT_EQ(dev.closes, 2);
  EXPECT_EQ(dev.still_mapped(), 0u);
  EXPECT_EQ(src.next(f, 10).code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace kg::platform
