#include "platform/v4l2/v4l2_source.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/mman.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <string>
#include <utility>

namespace kg::platform {
namespace {

// Pixel formats keygraph reads, cheapest to gray first.
struct Candidate {
  std::uint32_t fourcc;
  PixelFormat format;
  int rank;
};
constexpr Candidate kCandidates[] = {
    {V4L2_PIX_FMT_GREY, PixelFormat::kGrey, 0},    {V4L2_PIX_FMT_NV12, PixelFormat::kNv12, 1},
    {V4L2_PIX_FMT_NV12M, PixelFormat::kNv12, 1},   {V4L2_PIX_FMT_YUV420, PixelFormat::kYu12, 2},
    {V4L2_PIX_FMT_YUV420M, PixelFormat::kYu12, 2}, {V4L2_PIX_FMT_YUYV, PixelFormat::kYuyv, 3},
    {V4L2_PIX_FMT_UYVY, PixelFormat::kUyvy, 4},
};

const Candidate* find_candidate(std::uint32_t fourcc) {
  for (const Candidate& c : kCandidates) {
    if (c.fourcc == fourcc) return &c;
  }
  return nullptr;
}

std::string fourcc_string(std::uint32_t f) {
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((f >> (8 * i)) & 0xff);
    s += (c >= 32 && c < 127) ? c : '?';
  }
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

std::string errno_text(int err) {
  return std::string(std::strerror(err));
}

std::uint64_t monotonic_now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000u +
         static_cast<std::uint64_t>(ts.tv_nsec);
}

}  // namespace

V4l2Source::V4l2Source(V4l2Options options, v4l2::SystemIo& io)
    : options_(std::move(options)), io_(io) {}

V4l2Source::~V4l2Source() {
  stop();
}

std::string V4l2Source::prefix() const {
  return "v4l2: " + options_.device + ": ";
}

Status V4l2Source::fail(Status status) {
  error_ = status;
  return status;
}

std::string V4l2Source::description() const {
  std::string d = "v4l2 " + options_.device;
  if (fd_ < 0) return d + " (not started)";
  d += ": " + fourcc_string(fourcc_) + " " + std::to_string(layout_.width) + "x" +
       std::to_string(layout_.height) + " stride " + std::to_string(layout_.stride) + ", " +
       std::to_string(buffers_.size()) + " mmap buffers" +
       (multiplanar_ ? ", multi-planar API" : "") +
       (is_zero_copy(layout_.format) ? ", zero-copy gray" : ", converted to gray");
  return d;
}

// Retries ioctls interrupted by signals.
static int xioctl(v4l2::SystemIo& io, int fd, unsigned long request, void* arg) {
  int r;
  do {
    r = io.ioctl(fd, request, arg);
  } while (r == -1 && errno == EINTR);
  return r;
}

Status V4l2Source::open_device() {
  fd_ = io_.open(options_.device.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    const int err = errno;
    if (err == ENOENT) {
      return {StatusCode::kNotFound, prefix() + "no such device (" + errno_text(err) + ")"};
    }
    if (err == EACCES) {
      return {StatusCode::kIoError,
              prefix() + "permission denied (is the user in the 'video' group?)"};
    }
    return {StatusCode::kIoError, prefix() + "cannot open: " + errno_text(err)};
  }
  struct stat st {};
  if (io_.fstat(fd_, &st) != 0) {
    return {StatusCode::kIoError, prefix() + "fstat failed: " + errno_text(errno)};
  }
  if (!S_ISCHR(st.st_mode)) {
    return {StatusCode::kInvalidArgument, prefix() + "not a V4L2 device (not a character device)"};
  }
  v4l2_capability cap{};
  if (xioctl(io_, fd_, VIDIOC_QUERYCAP, &cap) != 0) {
    return {StatusCode::kInvalidArgument,
            prefix() + "not a V4L2 device (VIDIOC_QUERYCAP: " + errno_text(errno) + ")"};
  }
  const std::uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if (caps & V4L2_CAP_VIDEO_CAPTURE) {
    multiplanar_ = false;
  } else if (caps & V4L2_CAP_VIDEO_CAPTURE_MPLANE) {
    multiplanar_ = true;
  } else {
    return {StatusCode::kInvalidArgument,
            prefix() + "not a video capture device (driver " +
                std::string(reinterpret_cast<const char*>(cap.driver)) + ")"};
  }
  if (!(caps & V4L2_CAP_STREAMING)) {
    return {StatusCode::kInvalidArgument,
            prefix() + "the driver does not support streaming I/O (VIDIOC_STREAMON)"};
  }
  return Status::ok();
}

Status V4l2Source::negotiate_format() {
  const std::uint32_t type =
      multiplanar_ ? V4L2_BUF_TYPE_VIDEO_CAPTURE_MPLANE : V4L2_BUF_TYPE_VIDEO_CAPTURE;
  std::vector<const Candidate*> usable;
  std::string offered;
  for (std::uint32_t i = 0; i < 256; ++i) {
    v4l2_fmtdesc desc{};
    desc.index = i;
    desc.type = type;
    if (xioctl(io_, fd_, VIDIOC_ENUM_FMT, &desc) != 0) break;  // EINVAL: end of the list
    offered += (offered.empty() ? "" : ", ") + fourcc_string(desc.pixelformat);
    if (desc.flags & V4L2_FMT_FLAG_COMPRESSED) continue;
    if (const Candidate* c = find_candidate(desc.pixelformat)) usable.push_back(c);
  }
  std::stable_sort(usable.begin(), usable.end(),
                   [](const Candidate* a, const Candidate* b) { return a->rank < b->rank; });
  const std::string wanted = "GREY, NV12, YU12, YUYV or UYVY";
  if (usable.empty()) {
    return {StatusCode::kInvalidArgument,
            prefix() + "no supported pixel format: the device offers " +
                (offered.empty() ? "none" : offered) + "; keygraph reads " + wanted};
  }
  for (const Candidate* c : usable) {
    v4l2_format fmt{};
    fmt.type = type;
    if (multiplanar_) {
      fmt.fmt.pix_mp.width = static_cast<std::uint32_t>(options_.width);
      fmt.fmt.pix_mp.height = static_cast<std::uint32_t>(options_.height);
      fmt.fmt.pix_mp.pixelformat = c->fourcc;
      fmt.fmt.pix_mp.field = V4L2_FIELD_ANY;
    } else {
      fmt.fmt.pix.width = static_cast<std::uint32_t>(options_.width);
      fmt.fmt.pix.height = static_cast<std::uint32_t>(options_.height);
      fmt.fmt.pix.pixelformat = c->fourcc;
      fmt.fmt.pix.field = V4L2_FIELD_ANY;
    }
    if (xioctl(io_, fd_, VIDIOC_S_FMT, &fmt) != 0) {
      const int err = errno;
      if (err == EBUSY) {
        return {StatusCode::kIoError,
                prefix() + "device busy (VIDIOC_S_FMT: is another program capturing?)"};
      }
      if (err == ENODEV) return {StatusCode::kIoError, prefix() + "device disconnected (ENODEV)"};
      continue;  // try the next format
    }
    std::uint32_t w, h, bpl, sizeimage, got;
    if (multiplanar_) {
      const v4l2_pix_format_mplane& p = fmt.fmt.pix_mp;
      w = p.width;
      h = p.height;
      got = p.pixelformat;
      bpl = p.plane_fmt[0].bytesperline;
      sizeimage = p.plane_fmt[0].sizeimage;
      mem_planes_ = std::clamp<unsigned>(p.num_planes, 1u, 3u);
    } else {
      const v4l2_pix_format& p = fmt.fmt.pix;
      w = p.width;
      h = p.height;
      got = p.pixelformat;
      bpl = p.bytesperline;
      sizeimage = p.sizeimage;
      mem_planes_ = 1;
    }
    if (got != c->fourcc) continue;  // the driver substituted another format
    fourcc_ = got;
    layout_.format = c->format;
    layout_.width = static_cast<int>(std::min<std::uint32_t>(w, 1u << 30));
    layout_.height = static_cast<int>(std::min<std::uint32_t>(h, 1u << 30));
    layout_.stride = bpl != 0 ? static_cast<std::ptrdiff_t>(bpl)
                              : static_cast<std::ptrdiff_t>(min_stride(c->format, layout_.width));
    if (Status s = check_layout(layout_); !s) {
      return {StatusCode::kInvalidArgument,
              prefix() + "the driver chose an unusable " + s.message()};
    }
    // A whole frame: every plane when they share one buffer, the luma plane
    // alone when the multi-planar API gives each plane its own buffer. A
    // driver that promises less (sizeimage) is trusted down to the luma bytes.
    const std::size_t full = mem_planes_ > 1 ? static_cast<std::size_t>(layout_.stride) *
                                                   static_cast<std::size_t>(layout_.height)
                                             : frame_bytes(layout_);
    expected_bytes_ = std::max(luma_bytes(layout_),
                               sizeimage != 0 ? std::min<std::size_t>(full, sizeimage) : full);
    return Status::ok();
  }
  return {StatusCode::kInvalidArgument, prefix() + "the driver refused every supported format (" +
                                            wanted + "); it offers " + offered};
}

Status V4l2Source::allocate_buffers() {
  const std::uint32_t type =
      multiplanar_ ? V4L2_BUF_TYPE_VIDEO_CAPTURE_MPLANE : V4L2_BUF_TYPE_VIDEO_CAPTURE;
  v4l2_requestbuffers req{};
  req.count = std::max(2u, options_.buffer_count);
  req.type = type;
  req.memory = V4L2_MEMORY_MMAP;
  if (xioctl(io_, fd_, VIDIOC_REQBUFS, &req) != 0) {
    const int err = errno;
    if (err == EINVAL) {
      return {StatusCode::kInvalidArgument,
              prefix() + "the driver does not support memory-mapped streaming"};
    }
    return {StatusCode::kIoError, prefix() + "VIDIOC_REQBUFS failed: " + errno_text(err)};
  }
  if (req.count < 2) {
    return {StatusCode::kResourceExhausted, prefix() + "the driver granted " +
                                                std::to_string(req.count) +
                                                " buffer(s); streaming needs at least 2"};
  }
  buffers_.resize(req.count);
  for (std::uint32_t i = 0; i < req.count; ++i) {
    v4l2_buffer buf{};
    v4l2_plane planes[VIDEO_MAX_PLANES]{};
    buf.type = type;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = i;
    if (multiplanar_) {
      buf.m.planes = planes;
      buf.length = mem_planes_;
    }
    if (xioctl(io_, fd_, VIDIOC_QUERYBUF, &buf) != 0) {
      return {StatusCode::kIoError,
              prefix() + "VIDIOC_QUERYBUF " + std::to_string(i) + " failed: " + errno_text(errno)};
    }
    const unsigned count = multiplanar_ ? std::min<unsigned>(buf.length, mem_planes_) : 1;
    for (unsigned p = 0; p < count; ++p) {
      const std::size_t length = multiplanar_ ? planes[p].length : buf.length;
      const off_t offset = static_cast<off_t>(multiplanar_ ? planes[p].m.mem_offset : buf.m.offset);
      void* addr = io_.mmap(length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, offset);
      if (addr == MAP_FAILED) {
        return {StatusCode::kIoError,
                prefix() + "mmap of buffer " + std::to_string(i) + " failed: " + errno_text(errno)};
      }
      buffers_[i].planes[p] = {addr, length};
    }
    if (buffers_[i].planes[0].length < expected_bytes_) {
      return {StatusCode::kIoError, prefix() + "buffer " + std::to_string(i) + " holds " +
                                        std::to_string(buffers_[i].planes[0].length) +
                                        " bytes; the frame needs " +
                                        std::to_string(expected_bytes_)};
    }
  }
  if (!is_zero_copy(layout_.format)) {
    gray_.assign(static_cast<std::size_t>(layout_.width) * static_cast<std::size_t>(layout_.height),
                 0);
  }
  return Status::ok();
}

Status V4l2Source::queue_buffer(unsigned index) {
  v4l2_buffer buf{};
  v4l2_plane planes[VIDEO_MAX_PLANES]{};
  buf.type = multiplanar_ ? V4L2_BUF_TYPE_VIDEO_CAPTURE_MPLANE : V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.memory = V4L2_MEMORY_MMAP;
  buf.index = index;
  if (multiplanar_) {
    buf.m.planes = planes;
    buf.length = mem_planes_;
  }
  if (xioctl(io_, fd_, VIDIOC_QBUF, &buf) != 0) {
    const int err = errno;
    if (err == ENODEV) return {StatusCode::kIoError, prefix() + "device disconnected (ENODEV)"};
    return {StatusCode::kIoError,
            prefix() + "VIDIOC_QBUF " + std::to_string(index) + " failed: " + errno_text(err)};
  }
  return Status::ok();
}

Status V4l2Source::start() {
  stop();
  Status s = open_device();
  if (s) s = negotiate_format();
  if (s) s = allocate_buffers();
  for (unsigned i = 0; s && i < buffers_.size(); ++i) s = queue_buffer(i);
  if (s) {
    int type = multiplanar_ ? V4L2_BUF_TYPE_VIDEO_CAPTURE_MPLANE : V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(io_, fd_, VIDIOC_STREAMON, &type) != 0) {
      s = {StatusCode::kIoError, prefix() + "VIDIOC_STREAMON failed: " + errno_text(errno)};
    } else {
      streaming_ = true;
    }
  }
  if (!s) stop();
  return s;
}

// Dequeues one buffer: ok with `out` filled, ok with `again` set when no
// buffer was ready (EAGAIN), or an error.
Status V4l2Source::dequeue(Frame& out, bool& again) {
  again = false;
  v4l2_buffer buf{};
  v4l2_plane planes[VIDEO_MAX_PLANES]{};
  buf.type = multiplanar_ ? V4L2_BUF_TYPE_VIDEO_CAPTURE_MPLANE : V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.memory = V4L2_MEMORY_MMAP;
  if (multiplanar_) {
    buf.m.planes = planes;
    buf.length = mem_planes_;
  }
  if (xioctl(io_, fd_, VIDIOC_DQBUF, &buf) != 0) {
    const int err = errno;
    if (err == EAGAIN) {
      again = true;
      return Status::ok();
    }
    if (err == ENODEV)
      return fail({StatusCode::kIoError, prefix() + "device disconnected (ENODEV)"});
    if (err == EIO || err == EPIPE) {
      return fail({StatusCode::kIoError,
                   prefix() + "the driver stopped the stream after an error (VIDIOC_DQBUF: " +
                       errno_text(err) + ")"});
    }
    return fail({StatusCode::kIoError, prefix() + "VIDIOC_DQBUF failed: " + errno_text(err)});
  }
  if (buf.index >= buffers_.size()) {
    return fail({StatusCode::kIoError, prefix() + "driver returned buffer " +
                                           std::to_string(buf.index) + " of " +
                                           std::to_string(buffers_.size())});
  }
  const Plane& plane = buffers_[buf.index].planes[0];
  std::size_t offset = 0;
  std::size_t used = buf.bytesused;
  if (multiplanar_) {
    offset = std::min<std::size_t>(planes[0].data_offset, planes[0].bytesused);
    used = planes[0].bytesused - offset;
  }
  used = std::min(used, plane.length - std::min(offset, plane.length));
  std::string bad;
  if (buf.flags & V4L2_BUF_FLAG_ERROR) {
    bad = prefix() + "frame " + std::to_string(buf.sequence) + " flagged as corrupt by the driver";
  } else if (used < expected_bytes_) {
    bad = prefix() + "short buffer: frame " + std::to_string(buf.sequence) + " has " +
          std::to_string(used) + " of " + std::to_string(expected_bytes_) + " bytes (" +
          fourcc_string(fourcc_) + " " + std::to_string(layout_.width) + "x" +
          std::to_string(layout_.height) + ")";
  }
  Status s;
  if (bad.empty()) {
    s = to_gray(layout_, static_cast<const std::uint8_t*>(plane.addr) + offset, used, gray_.data(),
                gray_.size(), out.image);
    if (!s) bad = prefix() + s.message();
  }
  if (!bad.empty()) {
    if (Status q = queue_buffer(buf.index); !q) return fail(q);
    return {kBadFrameCode, bad};
  }
  held_ = static_cast<int>(buf.index);
  if ((buf.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
    out.timestamp_ns = static_cast<std::uint64_t>(buf.timestamp.tv_sec) * 1000000000u +
                       static_cast<std::uint64_t>(buf.timestamp.tv_usec) * 1000u;
  } else {
    out.timestamp_ns = monotonic_now_ns();
  }
  out.sequence = buf.sequence;
  return Status::ok();
}

Status V4l2Source::next(Frame& out, int timeout_ms) {
  if (!error_) return error_;
  if (!streaming_) return {StatusCode::kInvalidArgument, prefix() + "next() before start()"};
  if (held_ >= 0) {
    const unsigned index = static_cast<unsigned>(held_);
    held_ = -1;
    if (Status s = queue_buffer(index); !s) return fail(s);
  }
  using Clock = std::chrono::steady_clock;
  const Clock::time_point deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
  for (;;) {
    int wait_ms = -1;
    if (timeout_ms >= 0) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      wait_ms = static_cast<int>(std::max<decltype(left)>(0, left));
    }
    pollfd p{fd_, POLLIN, 0};
    const int r = io_.poll(&p, 1, wait_ms);
    if (r < 0) {
      if (errno == EINTR) continue;
      return fail({StatusCode::kIoError, prefix() + "poll failed: " + errno_text(errno)});
    }
    if (r == 0) {
      return {kTimeoutCode, prefix() + "no frame within " + std::to_string(timeout_ms) + " ms"};
    }
    if (p.revents & POLLNVAL) {
      return fail({StatusCode::kIoError, prefix() + "poll: descriptor no longer valid"});
    }
    bool again = false;
    Status s = dequeue(out, again);
    if (!s || !again) return s;
    // EAGAIN: nothing ready after all. With POLLERR the queue is dead.
    if (p.revents & (POLLERR | POLLHUP)) {
      return fail({StatusCode::kIoError,
                   prefix() + "the device reported an error (POLLERR) and delivers no frames"});
    }
    if (wait_ms == 0) {
      return {kTimeoutCode, prefix() + "no frame within " + std::to_string(timeout_ms) + " ms"};
    }
  }
}

void V4l2Source::stop() {
  if (fd_ >= 0 && streaming_) {
    int type = multiplanar_ ? V4L2_BUF_TYPE_VIDEO_CAPTURE_MPLANE : V4L2_BUF_TYPE_VIDEO_CAPTURE;
    (void)xioctl(io_, fd_, VIDIOC_STREAMOFF, &type);  // fails harmlessly on a vanished device
  }
  streaming_ = false;
  const bool had_buffers = !buffers_.empty();
  for (Buffer& b : buffers_) {
    for (Plane& p : b.planes) {
      if (p.addr != nullptr) io_.munmap(p.addr, p.length);
      p = {};
    }
  }
  buffers_.clear();
  if (fd_ >= 0) {
    if (had_buffers) {
      v4l2_requestbuffers req{};
      req.count = 0;
      req.type = multiplanar_ ? V4L2_BUF_TYPE_VIDEO_CAPTURE_MPLANE : V4L2_BUF_TYPE_VIDEO_CAPTURE;
      req.memory = V4L2_MEMORY_MMAP;
      (void)xioctl(io_, fd_, VIDIOC_REQBUFS, &req);
    }
    io_.close(fd_);
    fd_ = -1;
  }
  gray_ = {};
  held_ = -1;
  expected_bytes_ = 0;
  error_ = Status::ok();
}

}  // namespace kg::platform
