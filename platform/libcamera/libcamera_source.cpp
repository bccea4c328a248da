#include "platform/libcamera/libcamera_source.h"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <map>
#include <mutex>
#include <utility>

#include <libcamera/libcamera.h>

#include "platform/convert.h"

namespace kg::platform {
namespace lc = libcamera;

namespace {

std::string errno_text(int negative_errno) {
  return std::strerror(-negative_errno);
}

// libcamera allows one CameraManager per process (a second one is a fatal
// error inside libcamera), so every source shares this one. A weak_ptr
// expires before its deleter runs, so the last owner may still be
// destroying the manager on another thread when the next one is wanted:
// `g_manager_alive` stays true until the destructor has returned, and a new
// manager waits for it.
std::mutex g_manager_mutex;
std::condition_variable g_manager_destroyed;
std::weak_ptr<lc::CameraManager> g_manager;
bool g_manager_alive = false;

void destroy_manager(lc::CameraManager* manager) {
  delete manager;  // stops the manager; no new one starts meanwhile
  {
    std::lock_guard<std::mutex> lock(g_manager_mutex);
    g_manager_alive = false;
  }
  g_manager_destroyed.notify_all();
}

Status acquire_manager(std::shared_ptr<lc::CameraManager>& out) {
  out.reset();  // outside the lock: it may run the deleter
  std::unique_lock<std::mutex> lock(g_manager_mutex);
  for (;;) {
    out = g_manager.lock();
    if (out) return Status::ok();
    if (!g_manager_alive) break;
    g_manager_destroyed.wait(lock);
  }
  g_manager_alive = true;
  std::shared_ptr<lc::CameraManager> manager(new lc::CameraManager, destroy_manager);
  if (const int r = manager->start(); r < 0) {
    lock.unlock();  // the deleter takes the lock
    manager.reset();
    return {StatusCode::kIoError,
            "libcamera: the camera manager failed to start: " + errno_text(r)};
  }
  g_manager = manager;
  out = std::move(manager);
  return Status::ok();
}

struct Candidate {
  lc::PixelFormat lc_format;
  PixelFormat format;
};
// Cheapest to gray first.
const Candidate kCandidates[] = {
    {lc::formats::R8, PixelFormat::kGrey},     {lc::formats::NV12, PixelFormat::kNv12},
    {lc::formats::YUV420, PixelFormat::kYu12}, {lc::formats::YUYV, PixelFormat::kYuyv},
    {lc::formats::UYVY, PixelFormat::kUyvy},
};

const Candidate* find_candidate(const lc::PixelFormat& f) {
  for (const Candidate& c : kCandidates) {
    if (c.lc_format == f) return &c;
  }
  return nullptr;
}

}  // namespace

struct LibcameraSource::State {
  // Declared in dependency order: destroyed bottom-up.
  std::shared_ptr<lc::CameraManager> manager;
  std::shared_ptr<lc::Camera> camera;
  bool acquired = false;
  bool started = false;
  bool connected = false;
  std::unique_ptr<lc::CameraConfiguration> config;
  lc::Stream* stream = nullptr;
  std::unique_ptr<lc::FrameBufferAllocator> allocator;
  std::vector<std::unique_ptr<lc::Request>> requests;
  struct Mapping {
    void* addr = nullptr;
    std::size_t length = 0;
  };
  std::vector<Mapping> mappings;
  std::map<const lc::FrameBuffer*, const std::uint8_t*> luma;  // plane 0 pixels per buffer
  FrameLayout layout;
  std::size_t luma_length = 0;  // bytes of plane 0
  std::vector<std::uint8_t> gray;
  std::string description;

  // Completed requests, filled on libcamera's thread: a ring as large as the
  // number of requests, so handing a frame over never allocates.
  std::mutex mutex;
  std::condition_variable ready;
  std::vector<lc::Request*> ring;
  std::size_t head = 0;
  std::size_t count = 0;
  bool disconnected = false;

  lc::Request* held = nullptr;  // behind the frame the caller holds
  Status error;                 // sticky failure

  void on_request_completed(lc::Request* request) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (count < ring.size()) {
        ring[(head + count) % ring.size()] = request;
        ++count;
      }
    }
    ready.notify_one();
  }
  void on_disconnected() {
    {
      std::lock_guard<std::mutex> lock(mutex);
      disconnected = true;
    }
    ready.notify_one();
  }
};

Status list_libcamera_cameras(std::vector<std::string>& ids) {
  ids.clear();
  std::shared_ptr<lc::CameraManager> manager;
  if (Status s = acquire_manager(manager); !s) return s;
  for (const std::shared_ptr<lc::Camera>& c : manager->cameras()) ids.push_back(c->id());
  return Status::ok();
}

LibcameraSource::LibcameraSource(LibcameraOptions options) : options_(std::move(options)) {}

LibcameraSource::~LibcameraSource() {
  stop();
}

std::string LibcameraSource::description() const {
  if (!state_)
    return "libcamera " + (options_.camera_id.empty() ? "(first camera)" : options_.camera_id) +
           " (not started)";
  return state_->description;
}

Status LibcameraSource::start() {
  stop();
  state_ = std::make_unique<State>();
  State& st = *state_;
  auto fail = [this](StatusCode code, const std::string& message) {
    stop();
    return Status(code, "libcamera: " + message);
  };
  if (Status s = acquire_manager(st.manager); !s) {
    stop();
    return s;
  }
  const std::vector<std::shared_ptr<lc::Camera>> cameras = st.manager->cameras();
  if (options_.camera_id.empty()) {
    if (cameras.empty())
      return fail(StatusCode::kNotFound, "no camera device (the camera manager lists none)");
    st.camera = cameras.front();
  } else {
    st.camera = st.manager->get(options_.camera_id);
    if (!st.camera) {
      std::string known;
      for (const auto& c : cameras) known += (known.empty() ? "" : ", ") + c->id();
      return fail(StatusCode::kNotFound, "no camera with id '" + options_.camera_id +
                                             "' (cameras: " + (known.empty() ? "none" : known) +
                                             ")");
    }
  }
  const std::string id = st.camera->id();
  if (const int r = st.camera->acquire(); r < 0) {
    return fail(StatusCode::kIoError,
                id + ": cannot acquire the camera (" + errno_text(r) +
                    (r == -EBUSY ? "; in use by another program or source" : "") + ")");
  }
  st.acquired = true;

  st.config = st.camera->generateConfiguration({lc::StreamRole::Viewfinder});
  if (!st.config || st.config->size() != 1) {
    return fail(StatusCode::kInvalidArgument, id + ": no viewfinder stream configuration");
  }
  lc::StreamConfiguration& sc = st.config->at(0);
  const std::vector<lc::PixelFormat> offered = sc.formats().pixelformats();
  const Candidate* chosen = nullptr;
  for (const Candidate& c : kCandidates) {
    if (std::find(offered.begin(), offered.end(), c.lc_format) != offered.end()) {
      chosen = &c;
      break;
    }
  }
  if (chosen == nullptr) {
    std::string list;
    for (const lc::PixelFormat& f : offered) list += (list.empty() ? "" : ", ") + f.toString();
    return fail(StatusCode::kInvalidArgument,
                id + ": no supported pixel format: the camera offers " +
                    (list.empty() ? "none" : list) +
                    "; keygraph reads R8, NV12, YUV420, YUYV or UYVY");
  }
  sc.pixelFormat = chosen->lc_format;
  sc.size = lc::Size(static_cast<unsigned>(options_.width), static_cast<unsigned>(options_.height));
  sc.bufferCount = std::max(2u, options_.buffer_count);
  if (st.config->validate() == lc::CameraConfiguration::Invalid) {
    return fail(StatusCode::kInvalidArgument,
                id + ": configuration " + sc.toString() + " rejected");
  }
  chosen = find_candidate(sc.pixelFormat);  // validate() may have adjusted it
  if (chosen == nullptr) {
    return fail(
        StatusCode::kInvalidArgument,
        id + ": the camera adjusted the format to unsupported " + sc.pixelFormat.toString());
  }
  if (const int r = st.camera->configure(st.config.get()); r < 0) {
    return fail(StatusCode::kIoError,
                id + ": configure " + sc.toString() + " failed: " + errno_text(r));
  }
  st.stream = sc.stream();
  st.layout.format = chosen->format;
  st.layout.width = static_cast<int>(sc.size.width);
  st.layout.height = static_cast<int>(sc.size.height);
  st.layout.stride = sc.stride != 0
                         ? static_cast<std::ptrdiff_t>(sc.stride)
                         : static_cast<std::ptrdiff_t>(min_stride(chosen->format, st.layout.width));
  if (Status s = check_layout(st.layout); !s) {
    return fail(StatusCode::kInvalidArgument, id + ": unusable " + s.message());
  }
  const std::size_t needed = luma_bytes(st.layout);

  st.allocator = std::make_unique<lc::FrameBufferAllocator>(st.camera);
  if (const int r = st.allocator->allocate(st.stream); r < 0) {
    return fail(StatusCode::kResourceExhausted,
                id + ": buffer allocation failed: " + errno_text(r));
  }
  const std::vector<std::unique_ptr<lc::FrameBuffer>>& buffers = st.allocator->buffers(st.stream);
  if (buffers.size() < 2) {
    return fail(StatusCode::kResourceExhausted, id + ": " + std::to_string(buffers.size()) +
                                                    " buffer(s) allocated; need at least 2");
  }
  for (std::size_t i = 0; i < buffers.size(); ++i) {
    const lc::FrameBuffer* fb = buffers[i].get();
    const std::vector<lc::FrameBuffer::Plane>& planes = fb->planes();
    if (planes.empty()) return fail(StatusCode::kIoError, id + ": buffer without planes");
    // Map every dmabuf once, large enough for all the planes it holds, after
    // checking each plane against the dmabuf's size.
    std::map<int, std::size_t> extent;  // fd -> bytes to map
    for (std::size_t p = 0; p < planes.size(); ++p) {
      const lc::FrameBuffer::Plane& plane = planes[p];
      const int fd = plane.fd.get();
      const std::string what = "buffer " + std::to_string(i) + " plane " + std::to_string(p);
      if (fd < 0 || plane.offset == lc::FrameBuffer::Plane::kInvalidOffset) {
        return fail(StatusCode::kIoError, id + ": " + what + " has no valid fd/offset");
      }
      const std::size_t end = static_cast<std::size_t>(plane.offset) + plane.length;
      const off_t size = ::lseek(fd, 0, SEEK_END);
      if (size >= 0 && end > static_cast<std::size_t>(size)) {
        return fail(StatusCode::kIoError,
                    id + ": " + what + " (offset " + std::to_string(plane.offset) + ", length " +
                        std::to_string(plane.length) + ") ends past its dmabuf of " +
                        std::to_string(size) + " bytes");
      }
      extent[fd] = std::max(extent[fd], end);
    }
    if (planes[0].length < needed) {
      return fail(StatusCode::kIoError, id + ": buffer " + std::to_string(i) +
                                            " luma plane holds " +
                                            std::to_string(planes[0].length) + " bytes; " +
                                            std::to_string(needed) + " needed");
    }
    std::map<int, const std::uint8_t*> base;
    for (const auto& [fd, length] : extent) {
      void* addr = ::mmap(nullptr, length, PROT_READ, MAP_SHARED, fd, 0);
      if (addr == MAP_FAILED) {
        return fail(StatusCode::kIoError, id + ": mmap of buffer " + std::to_string(i) +
                                              " failed: " + errno_text(-errno));
      }
      st.mappings.push_back({addr, length});
      base[fd] = static_cast<const std::uint8_t*>(addr);
    }
    st.luma[fb] = base[planes[0].fd.get()] + planes[0].offset;
    st.luma_length = planes[0].length;

    std::unique_ptr<lc::Request> request = st.camera->createRequest(i);
    if (!request) return fail(StatusCode::kResourceExhausted, id + ": cannot create a request");
    if (const int r = request->addBuffer(st.stream, buffers[i].get()); r < 0) {
      return fail(StatusCode::kIoError, id + ": cannot add buffer " + std::to_string(i) +
                                            " to its request: " + errno_text(r));
    }
    st.requests.push_back(std::move(request));
  }
  if (!is_zero_copy(st.layout.format)) {
    st.gray.assign(
        static_cast<std::size_t>(st.layout.width) * static_cast<std::size_t>(st.layout.height), 0);
  }
  st.ring.assign(st.requests.size(), nullptr);

  st.camera->requestCompleted.connect(&st, &State::on_request_completed);
  st.camera->disconnected.connect(&st, &State::on_disconnected);
  st.connected = true;
  if (const int r = st.camera->start(); r < 0) {
    return fail(StatusCode::kIoError, id + ": start failed: " + errno_text(r));
  }
  st.started = true;
  for (std::unique_ptr<lc::Request>& request : st.requests) {
    if (const int r = st.camera->queueRequest(request.get()); r < 0) {
      return fail(StatusCode::kIoError, id + ": queueing a request failed: " + errno_text(r));
    }
  }
  st.description = "libcamera " + id + ": " + sc.pixelFormat.toString() + " " +
                   std::to_string(st.layout.width) + "x" + std::to_string(st.layout.height) +
                   " stride " + std::to_string(st.layout.stride) + ", " +
                   std::to_string(st.requests.size()) + " buffers" +
                   (is_zero_copy(st.layout.format) ? ", zero-copy gray" : ", converted to gray");
  return Status::ok();
}

Status LibcameraSource::next(Frame& out, int timeout_ms) {
  if (!state_ || !state_->started) {
    return {StatusCode::kInvalidArgument, "libcamera: next() before start()"};
  }
  State& st = *state_;
  if (!st.error) return st.error;
  const std::string& id = st.camera->id();
  auto requeue = [&st, &id](lc::Request* request) -> Status {
    request->reuse(lc::Request::ReuseBuffers);
    if (const int r = st.camera->queueRequest(request); r < 0) {
      st.error = Status(StatusCode::kIoError,
                        "libcamera: " + id + ": queueing a request failed: " + errno_text(r));
      return st.error;
    }
    return Status::ok();
  };
  if (st.held != nullptr) {
    lc::Request* request = st.held;
    st.held = nullptr;
    if (Status s = requeue(request); !s) return s;
  }

  lc::Request* request = nullptr;
  {
    std::unique_lock<std::mutex> lock(st.mutex);
    auto has_news = [&st] { return st.count > 0 || st.disconnected; };
    if (timeout_ms < 0) {
      st.ready.wait(lock, has_news);
    } else {
      st.ready.wait_for(lock, std::chrono::milliseconds(timeout_ms), has_news);
    }
    if (st.disconnected) {
      st.error = Status(StatusCode::kIoError, "libcamera: " + id + ": camera disconnected");
      return st.error;
    }
    if (st.count == 0) {
      return {kTimeoutCode,
              "libcamera: " + id + ": no frame within " + std::to_string(timeout_ms) + " ms"};
    }
    request = st.ring[st.head];
    st.head = (st.head + 1) % st.ring.size();
    --st.count;
  }

  const lc::FrameBuffer* fb = request->findBuffer(st.stream);
  std::string bad;
  if (request->status() != lc::Request::RequestComplete || fb == nullptr) {
    bad = "request cancelled";
  } else if (fb->metadata().status != lc::FrameMetadata::FrameSuccess) {
    bad = "frame " + std::to_string(fb->metadata().sequence) + " failed in the pipeline";
  } else {
    const lc::FrameMetadata& md = fb->metadata();
    const std::size_t used =
        md.planes().empty() ? 0 : std::min<std::size_t>(md.planes()[0].bytesused, st.luma_length);
    const auto it = st.luma.find(fb);
    if (it == st.luma.end()) {
      bad = "completed buffer is not one of ours";
    } else if (Status s =
                   to_gray(st.layout, it->second, used, st.gray.data(), st.gray.size(), out.image);
               !s) {
      bad = "frame " + std::to_string(md.sequence) + ": " + s.message();
    } else {
      out.timestamp_ns = md.timestamp;
      out.sequence = md.sequence;
    }
  }
  if (!bad.empty()) {
    if (Status s = requeue(request); !s) return s;
    return {kBadFrameCode, "libcamera: " + id + ": " + bad};
  }
  st.held = request;
  return Status::ok();
}

void LibcameraSource::stop() {
  if (!state_) return;
  State& st = *state_;
  if (st.started) st.camera->stop();  // completes pending requests as cancelled
  st.started = false;
  if (st.connected) {
    st.camera->requestCompleted.disconnect(&st, &State::on_request_completed);
    st.camera->disconnected.disconnect(&st, &State::on_disconnected);
    st.connected = false;
  }
  st.held = nullptr;
  st.requests.clear();
  for (const State::Mapping& m : st.mappings) ::munmap(m.addr, m.length);
  st.mappings.clear();
  if (st.allocator && st.stream != nullptr) st.allocator->free(st.stream);
  st.allocator.reset();
  st.config.reset();
  if (st.acquired) st.camera->release();
  st.acquired = false;
  st.camera.reset();
  st.manager.reset();
  state_.reset();
}

}  // namespace kg::platform
