// keygraph live: its options are the Options table below (keygraph live --help).
// Follows the index's objects through the frames of a camera, of image
// files or of a video file (OpenCV videoio, desktop builds) with kg::Tracker
// (keygraph/tracker.h: detection when nothing is followed, when an object is
// lost and every few frames; an alignment per object on the others), or
// detects on every frame with --no-track. stdout gets the lines of
// `keygraph detect` (with --json, its JSON lines) plus each detection's
// track and whether the frame was detected on; stderr gets the source's
// description, a frames-per-second line about once a
// second, and a summary at the end (frames tracked and detected, and the
// mean time of each). Ctrl-C (SIGINT) or SIGTERM finishes the current
// frame, stops the source and exits 0.
#include <cerrno>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <system_error>

#include <sys/stat.h>

#include "cli/device/detect_settings.h"
#include "cli/device/detector_fit.h"
#include "cli/device/device_commands.h"
#include "cli/device/frame_output.h"
#include "cli/device/options.h"
#include "cli/device/stop_signal.h"
#include "keygraph/detector.h"
#include "keygraph/tracker.h"
#include "platform/files/file_source.h"
#include "platform/frame_source.h"
#if KG_CLI_HAVE_VIDEO
#include "platform/files/video_source.h"
#endif
#if KG_CLI_HAVE_V4L2
#include "platform/v4l2/v4l2_source.h"
#endif
#if KG_CLI_HAVE_LIBCAMERA
#include "platform/libcamera/libcamera_source.h"
#endif

namespace kg::cli {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// next() waits this long at most, so a stop request is seen within it.
constexpr int kPollMs = 250;
// A camera that delivers nothing for this long is reported as failed.
constexpr double kNoFrameLimitS = 10.0;
// Bad frames beyond this many are counted, not shown one by one.
constexpr int kShownBadFrames = 5;

enum class SourceKind { kNone, kV4l2, kLibcamera, kImages, kVideo };

struct LiveOptions {
  std::string index_path;
  SourceKind kind = SourceKind::kNone;
  std::string source;  // device path, camera id (may be empty), image or video path
  int width = 640, height = 480;
  bool size_given = false;
  bool loop = false;
  bool json = false;
  std::string draw_dir;
  int max_frames = 0;       // 0: no limit
  bool quiet = false;       // no status lines on stderr (warnings stay)
  bool no_track = false;    // detection alone on every frame
  DetectSettings settings;  // --set, --threads
};

double seconds(Clock::duration d) {
  return std::chrono::duration<double>(d).count();
}

// The options of live, bound to `o`.
Options live_options(LiveOptions& o) {
  auto source = [&o](SourceKind kind) {
    return [&o, kind](const std::string& value) -> std::string {
      if (o.kind != SourceKind::kNone)
        return "give one source: --v4l2, --libcamera, --images or --video";
      o.kind = kind;
      o.source = value;
      return {};
    };
  };
  Options options(
      "live",
      "--index I.kgi (--v4l2 /dev/videoN | --libcamera [ID] | --images PATH |\n"
      "       --video FILE) [--size WxH] [--loop] [--json] [--draw DIR] [--frames N]\n"
      "       [--no-track] [--set NAME=VALUE]... [--threads N] [-q]",
      "Follows the index's objects through the frames of a camera, of image files or of\n"
      "a video file: full detection when nothing is followed, when an object is lost\n"
      "and every 10th frame; on the other frames each object is confirmed around its\n"
      "predicted pose (a fraction of a detection's time) and keeps its track id. stdout\n"
      "gets the lines of keygraph detect with each detection's track, stderr the frames\n"
      "per second about once a second and a summary (frames tracked and detected, mean\n"
      "ms of each).\n"
      "Ctrl-C (SIGINT) or SIGTERM finishes the current frame and exits 0.");
  options
      .text("--index", "I.kgi", o.index_path,
            "the model index (required); reloaded when its file changes")
      .value("--v4l2", "DEV", "frames from a V4L2 camera, e.g. /dev/video0",
             source(SourceKind::kV4l2))
      .optional_value("--libcamera", "ID",
                      "frames from a libcamera camera (CSI); ID: its id, default the first",
                      source(SourceKind::kLibcamera))
      .value("--images", "PATH",
             "frames from an image file or a directory of them, in name order (byte order:\n"
             "number them with leading zeros, frame_0009 before frame_0010)",
             source(SourceKind::kImages))
      .value("--video", "FILE",
             "frames from a video file (AVI, MP4, MKV, ...; OpenCV videoio, desktop builds)",
             source(SourceKind::kVideo))
      .value(
          "--size", "WxH", "the camera's frame size in pixels (cameras only)",
          [&o](const std::string& v) -> std::string {
            if (!parse_size(v, o.width, o.height))
              return "--size " + v + ": expected WIDTHxHEIGHT, e.g. 640x480";
            o.size_given = true;
            return {};
          },
          std::to_string(o.width) + "x" + std::to_string(o.height))
      .flag("--loop", o.loop,
            "start the images or the video again after the last frame (--images and\n"
            "--video only)")
      .flag("--json", o.json, "one JSON object per frame on stdout (as keygraph detect --json)")
      .text("--draw", "DIR", o.draw_dir,
            "write each frame with the outlines and names found to DIR as PGM\n"
            "(frame_NNNNNN.pgm, NNNNNN the frame's number from 0; <image name>.pgm\n"
            "with --images)")
      .value(
          "--frames", "N", "stop after N frames, 1..1073741824",
          [&o](const std::string& v) -> std::string {
            if (!parse_int(v, 1, 1 << 30, o.max_frames))
              return "--frames " + v + ": not a count in 1.." + std::to_string(1 << 30);
            return {};
          },
          "no limit")
      .flag("--no-track", o.no_track,
            "detect on every frame, no tracking (each detection's track is -1 and\n"
            "tracked false; every frame counts as detected)")
      .flag("-q, --quiet", o.quiet,
            "no status on stderr: the source, the frames per second and the summary\n"
            "(warnings and errors stay)");
  o.settings.declare(options);
  options.example("keygraph live --index signs.kgi --v4l2 /dev/video0 --size 1280x720")
      .example("keygraph live --index signs.kgi --images frames/ --json --frames 100")
      .example("keygraph live --index signs.kgi --video drive.mp4 --json")
      .note(
          "JSON lines: those of keygraph detect --json, with \"detected\" after \"time_ms\"\n"
          "(false on a frame where every object was followed and no detection ran: its stats\n"
          "are then zero) and \"track\" (the object's id while it is followed, -1 otherwise)\n"
          "and \"tracked\" (true when confirmed around its prediction, false when detection\n"
          "found it on this frame) in each detection. An index without model appearances\n"
          "(built before format 6.2, or with views.appearance_size 0) cannot be tracked:\n"
          "every frame is then detected, and live says so once on stderr.");
  return options;
}

// The options that do not go together; returns an error message, or empty.
std::string usage_problem(const LiveOptions& o) {
  if (o.index_path.empty()) return "no index given (--index I.kgi)";
  if (o.kind == SourceKind::kNone)
    return "no frame source given (--v4l2 /dev/videoN, --libcamera [ID], --images DIR or "
           "--video FILE)";
  const bool from_files = o.kind == SourceKind::kImages || o.kind == SourceKind::kVideo;
  if (o.loop && !from_files) return "--loop applies to --images and --video only";
  if (o.size_given && from_files) return "--size applies to cameras only";
  return {};
}

// The --draw directory; returns an error message, or empty.
std::string check_draw(const LiveOptions& o) {
  if (!o.draw_dir.empty()) {
    std::error_code ec;
    if (!fs::is_directory(o.draw_dir, ec)) return "--draw " + o.draw_dir + ": no such directory";
    if (o.kind == SourceKind::kImages && fs::equivalent(o.draw_dir, o.source, ec))
      return "--draw " + o.draw_dir + " is the --images directory: pictures would replace frames";
  }
  return {};
}

// The source for the options, or an error message in `error`.
std::unique_ptr<platform::FrameSource> make_source(const LiveOptions& o, std::string& error) {
  switch (o.kind) {
    case SourceKind::kImages: {
      platform::FileSourceOptions options;
      options.loop = o.loop;
      return std::make_unique<platform::FileSource>(std::vector<std::string>{o.source}, options);
    }
    case SourceKind::kVideo: {
#if KG_CLI_HAVE_VIDEO
      platform::VideoSourceOptions options;
      options.loop = o.loop;
      return std::make_unique<platform::VideoSource>(o.source, options);
#else
      error =
          "--video: this keygraph was built without video support (no OpenCV videoio; "
          "read the frames as image files with --images)";
      return nullptr;
#endif
    }
    case SourceKind::kV4l2: {
#if KG_CLI_HAVE_V4L2
      platform::V4l2Options options;
      options.device = o.source;
      options.width = o.width;
      options.height = o.height;
      return std::make_unique<platform::V4l2Source>(options);
#else
      error = "--v4l2: this keygraph was built without the V4L2 source (no linux/videodev2.h)";
      return nullptr;
#endif
    }
    case SourceKind::kLibcamera: {
#if KG_CLI_HAVE_LIBCAMERA
      // libcamera logs INFO and WARN lines on stderr by default; keep only
      // its errors unless the user chose levels (LIBCAMERA_LOG_LEVELS).
      ::setenv("LIBCAMERA_LOG_LEVELS", "*:ERROR", 0);
      platform::LibcameraOptions options;
      options.camera_id = o.source;
      options.width = o.width;
      options.height = o.height;
      return std::make_unique<platform::LibcameraSource>(options);
#else
      error =
          "--libcamera: this keygraph was built without the libcamera source (libcamera not "
          "found, or KG_WITH_LIBCAMERA=OFF)";
      return nullptr;
#endif
    }
    case SourceKind::kNone:
      break;
  }
  error = "no frame source";
  return nullptr;
}

// What names the index file: when the path names another file (replaced by
// a rename, or rewritten in place by cp or scp), live loads it again.
struct FileIdentity {
  dev_t device = 0;
  ino_t inode = 0;
  off_t size = 0;
  timespec modified{};
  bool operator==(const FileIdentity& o) const {
    return device == o.device && inode == o.inode && size == o.size &&
           modified.tv_sec == o.modified.tv_sec && modified.tv_nsec == o.modified.tv_nsec;
  }
};

FileIdentity identity_of(const std::string& path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) return {};
  return {info.st_dev, info.st_ino, info.st_size, info.st_mtim};
}

// Loads the index at `path` into `index` (read into memory, never mapped:
// the file may be rewritten in place while live runs; model_index.h).
Status load_index(const std::string& path, ModelIndex& index) {
  ModelIndex loaded;
  if (Status s = ModelIndex::read(path, loaded); !s) return s;
  if (const std::string problem = core_detector_problem(loaded); !problem.empty())
    return {StatusCode::kInvalidArgument, path + ": " + problem};
  index = std::move(loaded);
  return Status::ok();
}

// The index live detects with, reloaded between frames when its file
// changes. A file that cannot be loaded (e.g. half copied) leaves the
// loaded index in use, with one line on stderr until a load succeeds.
class LiveIndex {
 public:
  explicit LiveIndex(std::string path) : path_(std::move(path)) {}
  Status load() {
    loaded_ = identity_of(path_);
    last_seen_ = loaded_;
    return load_index(path_, index_);
  }
  const ModelIndex& index() const { return index_; }
  // Between frames: true when the index was reloaded (the detector must be
  // rebuilt on it). One stat() call when nothing changed.
  bool reload_if_changed() {
    const FileIdentity now = identity_of(path_);
    if (now == loaded_ || now == last_seen_) return false;
    last_seen_ = now;
    ModelIndex fresh;
    if (Status s = load_index(path_, fresh); !s) {
      // Once until a load succeeds: a file being copied changes (and fails
      // to load) frame after frame.
      if (failure_reported_) return false;
      failure_reported_ = true;
      std::fprintf(stderr,
                   "keygraph: live: index changed but not reloaded (keeping the loaded one): %s\n",
                   one_line(s.message()).c_str());
      return false;
    }
    // The file may have changed again while it was read: compare with what
    // is there now, next frame.
    loaded_ = now;
    failure_reported_ = false;
    index_ = std::move(fresh);
    std::fprintf(stderr, "live: index %s changed: reloaded (%s)\n", one_line(path_).c_str(),
                 counted(index_.model_count(), "model").c_str());
    return true;
  }

 private:
  std::string path_;
  ModelIndex index_;
  FileIdentity loaded_, last_seen_;
  bool failure_reported_ = false;
};

// Frames per second over the last report interval (about a second).
class RateMeter {
 public:
  explicit RateMeter(Clock::time_point start) : window_start_(start) {}
  // Counts one frame; returns true when a report is due.
  bool frame(Clock::time_point now, double detect_ms) {
    ++frames_;
    detect_ms_ += detect_ms;
    return now - window_start_ >= std::chrono::seconds(1);
  }
  void report(Clock::time_point now, std::uint64_t total) {
    const double s = seconds(now - window_start_);
    std::fprintf(stderr, "live: %" PRIu64 " frames, %.1f fps, %.1f ms/frame (last %.1f s)\n", total,
                 frames_ / s, detect_ms_ / frames_, s);
    window_start_ = now;
    frames_ = 0;
    detect_ms_ = 0;
  }

 private:
  Clock::time_point window_start_;
  int frames_ = 0;
  double detect_ms_ = 0;
};

// Frames and their time, split by whether detection ran on them.
struct FrameTally {
  std::uint64_t tracked = 0, detected = 0;
  double tracked_ms = 0, detected_ms = 0;
  void add(bool detection_ran, double ms) {
    (detection_ran ? detected : tracked) += 1;
    (detection_ran ? detected_ms : tracked_ms) += ms;
  }
  // "3 tracked (mean 1.2 ms), 1 detected (mean 30.5 ms)"
  std::string text() const {
    const auto part = [](std::uint64_t n, double ms, const char* what) {
      char buf[96];
      if (n == 0) {
        std::snprintf(buf, sizeof(buf), "0 %s", what);
      } else {
        std::snprintf(buf, sizeof(buf), "%" PRIu64 " %s (mean %.1f ms)", n, what,
                      ms / static_cast<double>(n));
      }
      return std::string(buf);
    };
    return part(tracked, tracked_ms, "tracked") + ", " + part(detected, detected_ms, "detected");
  }
};

// The tracker over live's detector, made again whenever the detector is
// (a new index, a larger frame): a tracker is made for one detector's
// index and limits.
class LiveTracker {
 public:
  LiveTracker(bool enabled, bool quiet) : enabled_(enabled), quiet_(quiet) {}
  // Forgets the tracker (before the detector is replaced).
  void drop() { tracker_.reset(); }
  // Makes the tracker for `detector` when there is none or the detector's
  // frame size changed. An index without appearances is said once on
  // stderr, as a status line, not an error (the tracker then detects every
  // frame); any other failure is returned.
  Status fit(Detector& detector) {
    if (!enabled_) return Status::ok();
    const Limits& l = detector.limits();
    if (tracker_ != nullptr && l.max_width == width_ && l.max_height == height_)
      return Status::ok();
    tracker_ = std::make_unique<Tracker>(detector);
    width_ = l.max_width;
    height_ = l.max_height;
    if (tracker_->status()) return Status::ok();
    if (detector.index().has_appearance()) return tracker_->status();
    if (!untrackable_said_ && !quiet_) {
      std::fprintf(stderr,
                   "live: the index stores no model appearances (built before format "
                   "6.2, or with views.appearance_size 0): every frame is detected; rebuild it "
                   "with keygraph build to track\n");
      untrackable_said_ = true;
    }
    return Status::ok();
  }
  // The frame's objects, and whether detection ran on it.
  Status process(Detector& detector, ImageView frame, DetectionList& found, bool& detected) {
    if (!enabled_) {
      detected = true;
      return detector.detect(frame, found);
    }
    const Status s = tracker_->process(frame, found);
    detected = tracker_->stats().detected;
    return s;
  }

 private:
  bool enabled_, quiet_;
  std::unique_ptr<Tracker> tracker_;
  int width_ = 0, height_ = 0;
  bool untrackable_said_ = false;
};

}  // namespace

int cmd_live(const Args& args) {
  LiveOptions o;
  const Options options = live_options(o);
  if (const int exit_code = options.parse(args); exit_code >= 0) return exit_code;
  if (std::string error = usage_problem(o); !error.empty()) return options.usage_error(error);
  if (std::string error = check_draw(o); !error.empty()) return fail("live: " + error);
  LiveIndex live_index(o.index_path);
  if (Status s = live_index.load(); !s) return fail("live: " + s.message());
  DetectOptions runtime;
  if (Status s = o.settings.options_for(live_index.index(), runtime); !s)
    return options.usage_error(s.message());
  std::string error;
  std::unique_ptr<platform::FrameSource> source = make_source(o, error);
  if (source == nullptr) return fail("live: " + error);
  auto* files = dynamic_cast<platform::FileSource*>(source.get());

  // Everything the loop needs is allocated here, before the first frame.
  // The workspace is allocated here for 640x480 and again, once, if the
  // first frame (or a later, larger one) needs more.
  Detector detector(live_index.index(), o.settings.limits(), runtime);
  if (!detector.status()) return fail("live: " + detector.status().message());
  LiveTracker tracker(!o.no_track, o.quiet);
  if (Status t = tracker.fit(detector); !t) return fail("live: " + t.message());
  DetectionList found;
  platform::GrayImage canvas;
  std::string name;

  const StopSignal stop;
  if (Status s = source->start(); !s) return fail("live: " + s.message());
  if (files != nullptr && !o.draw_dir.empty()) {
    // One picture per image file, named after its stem: two files with one
    // stem (x.png, x.pgm) would overwrite each other's picture.
    std::map<std::string, const std::string*> by_stem;
    for (const std::string& f : files->files()) {
      const auto [it, inserted] = by_stem.emplace(fs::path(f).stem().string(), &f);
      if (!inserted && *it->second != f)
        return fail("live: --draw: " + *it->second + " and " + f + " would both be drawn to " +
                    (fs::path(o.draw_dir) / (it->first + ".pgm")).string() +
                    "; give the images distinct names");
    }
  }
  if (!o.quiet) std::fprintf(stderr, "live: %s\n", one_line(source->description()).c_str());

  const Clock::time_point start = Clock::now();
  RateMeter meter(start);
  Clock::time_point last_frame = start;
  std::uint64_t frames = 0, with_detections = 0;
  FrameTally tally;
  int bad_frames = 0;
  // Bad frames in a row: a whole pass of a looping file source without one
  // good frame would otherwise loop for ever.
  std::size_t bad_in_a_row = 0;
  std::string stopped_by = o.kind == SourceKind::kVideo ? "end of the video" : "end of the images";
  // Counts and shows a skipped frame; true when, with --loop, a whole pass
  // of the image files had no usable frame (the loop would never end).
  auto skip_frame = [&](const std::string& why) {
    if (++bad_frames <= kShownBadFrames) {
      std::fprintf(stderr, "keygraph: live: %s (frame skipped%s)\n", one_line(why).c_str(),
                   bad_frames == kShownBadFrames ? "; further bad frames are only counted" : "");
    }
    return files != nullptr && o.loop && ++bad_in_a_row >= files->files().size();
  };
  int exit_code = 0;
  for (;;) {
    if (const int sig = StopSignal::received(); sig != 0) {
      stopped_by = StopSignal::name(sig);
      break;
    }
    if (o.max_frames > 0 && frames >= static_cast<std::uint64_t>(o.max_frames)) {
      stopped_by = "--frames " + std::to_string(o.max_frames);
      break;
    }
    platform::Frame frame;
    const Status s = source->next(frame, kPollMs);
    if (platform::is_timeout(s)) {
      if (seconds(Clock::now() - last_frame) < kNoFrameLimitS) continue;
      exit_code = fail("live: no frame from " + source->description() + " for " +
                       std::to_string(static_cast<int>(kNoFrameLimitS)) + " s");
      stopped_by.clear();
      break;
    }
    if (platform::is_end_of_stream(s)) break;
    if (platform::is_bad_frame(s)) {
      if (skip_frame(s.message())) {
        exit_code = fail("live: none of the " + std::to_string(files->files().size()) +
                         " image files could be read");
        stopped_by.clear();
        break;
      }
      continue;
    }
    if (!s) {
      exit_code = fail("live: " + s.message());
      stopped_by.clear();
      break;
    }
    last_frame = Clock::now();

    if (live_index.reload_if_changed()) {
      tracker.drop();  // its tracks are of the old index's models
      Status rebuilt = o.settings.options_for(live_index.index(), runtime);
      if (rebuilt) {
        detector = Detector(live_index.index(), detector.limits(), runtime);
        rebuilt = detector.status();
      }
      if (!rebuilt) {
        exit_code = fail("live: " + rebuilt.message());
        stopped_by.clear();
        break;
      }
    }
    if (const Status fit = fit_detector(detector, frame.image); !fit) {
      // A video's frames share one size: skipping one would skip them all.
      if (o.kind == SourceKind::kVideo) {
        exit_code = fail("live: " + o.source + ": " + fit.message());
        stopped_by.clear();
        break;
      }
      if (skip_frame((files != nullptr ? files->last_path() + ": " : std::string()) +
                     fit.message())) {
        exit_code = fail("live: none of the " + std::to_string(files->files().size()) +
                         " image files is within the detector's limits");
        stopped_by.clear();
        break;
      }
      continue;
    }
    bad_in_a_row = 0;
    if (Status t = tracker.fit(detector); !t) {
      exit_code = fail("live: " + t.message());
      stopped_by.clear();
      break;
    }
    bool detected = true;
    const Status d = tracker.process(detector, frame.image, found, detected);
    const Clock::time_point done = Clock::now();
    const double ms = std::chrono::duration<double, std::milli>(done - last_frame).count();
    if (files != nullptr) {
      name = files->last_path();
    } else {
      name = o.source.empty() ? std::string("libcamera") : o.source;
      name += ':';
      name += std::to_string(frame.sequence);
    }
    if (!d) {
      exit_code = fail("live: " + name + ": " + d.message());
      stopped_by.clear();
      break;
    }
    ++frames;
    if (!found.empty()) ++with_detections;
    tally.add(detected, ms);
    // A frame without detection has no detection stats (zero, not the last
    // detected frame's).
    const TrackedFrame tracked{detected};
    print_detections(name, frame.image, ms, found, detected ? detector.stats() : DetectStats{},
                     o.json, &tracked);
    if (std::fflush(stdout) != 0) {
      // A closed pipe (e.g. `| head`) is a normal way to stop.
      stopped_by = "stdout closed";
      if (errno != EPIPE) {
        exit_code = fail("live: cannot write to stdout");
      } else {
        stdout_closed_by_reader();
      }
      break;
    }
    if (!o.draw_dir.empty()) {
      draw_outlines(frame.image, found, canvas);
      char numbered[32];
      std::snprintf(numbered, sizeof(numbered), "frame_%06" PRIu64 ".pgm", frame.sequence);
      const fs::path out = fs::path(o.draw_dir) /
                           (files != nullptr ? fs::path(name).stem().string() + ".pgm" : numbered);
      std::vector<std::string> inputs{o.index_path};
      if (files != nullptr) inputs.push_back(name);
      if (o.kind == SourceKind::kVideo) inputs.push_back(o.source);
      if (Status w = platform::write_pgm(out.string(), canvas.view(), inputs); !w) {
        exit_code = fail("live: " + w.message());
        stopped_by.clear();
        break;
      }
    }
    if (meter.frame(done, ms) && !o.quiet) meter.report(done, frames);
  }
  source->stop();

  const double total_s = seconds(Clock::now() - start);
  if (!o.quiet) {
    std::fprintf(stderr,
                 "live: %" PRIu64 " frame%s in %.1f s (%.1f fps), %" PRIu64
                 " with detections, %d bad frame%s skipped; %s%s%s\n",
                 frames, frames == 1 ? "" : "s", total_s,
                 total_s > 0 ? static_cast<double>(frames) / total_s : 0.0, with_detections,
                 bad_frames, bad_frames == 1 ? "" : "s", tally.text().c_str(),
                 stopped_by.empty() ? "" : "; stopped by ", stopped_by.c_str());
  }
  // Image files that could not be read are errors, as in `keygraph detect`;
  // a camera's occasional bad frame is not.
  if (exit_code == 0 && bad_frames > 0 && o.kind == SourceKind::kImages) exit_code = 1;
  return exit_code;
}

}  // namespace kg::cli
