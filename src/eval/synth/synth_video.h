// The synthetic video benchmark (`keygraph synth --video`): one sign of the
// catalogue on a real photo, filmed by a hand-held camera at 30 fps along a
// smooth path with five parts: an approach from far to near, fast pans, a
// brief occlusion (something passes in front), the sign leaving the frame
// and coming back, then turns in depth and in plane. Motion blur comes from
// the path itself: each frame averages sub-frames over the exposure.
//
//   DIR/video.jsonl        the ground truth, one line per frame in order
//   DIR/signs/NAME.png     the models: the catalogue's first N signs (BGR)
//   DIR/frames/NNNN.jpg    the frames (JPEG, quality 95)
//
// video.jsonl is the manifest of `keygraph eval --truth` (docs/EVAL.md)
// with every frame in order; a line without "instances" is a frame without
// ground truth (eval/video_manifest.h). The sign is an instance where at
// least kVisibleToFind of it shows (inside the frame, not hidden), the
// frame has no instance where at most kVisibleAbsent shows, and frames in
// between are not scored (a tracker may keep or drop a half-hidden sign).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "builder/progress.h"
#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg {

inline constexpr double kVisibleToFind = 0.75;
inline constexpr double kVisibleAbsent = 0.02;

struct SynthVideoOptions {
  std::string directory;    // created; must not exist or be empty
  std::string backgrounds;  // directory with opencv-doc's photos
  std::uint64_t seed = 1;
  int signs = 10;  // models written: the catalogue's first N; one of them is filmed
  int frames = 300;
  int width = 640, height = 480;
  double exposure = 0.5;  // fraction of the frame interval the shutter is open
};

// One rendered frame's ground truth.
struct SynthVideoFrame {
  std::string file;
  Point2f corners[4];     // the sign's outline at the middle of the exposure
  double visible = 0;     // fraction of the sign inside the frame and not hidden
  double blur_px = 0;     // longest corner path during the exposure, pixels
  const char* part = "";  // approach, pans, occlusion, leave, turns
};

struct SynthVideo {
  std::string sign_name;
  int sign = -1;  // catalogue id
  int sign_width = 0, sign_height = 0;
  std::vector<std::string> model_names, model_files;
  std::vector<SynthVideoFrame> frames;
};

// Renders the sequence, handing each image to `sink` (models first, then
// the frames in order; `file` relative to the directory).
using SynthVideoSink = std::function<Status(const std::string& file, const cv::Mat& image)>;
Status render_synth_video(const SynthVideoOptions& options, SynthVideo& video,
                          const SynthVideoSink& sink, const ProgressFn& progress = {});

// The manifest text (video.jsonl) of a rendered sequence.
std::string synth_video_manifest(const SynthVideoOptions& options, const SynthVideo& video);

// Renders and writes the sequence into options.directory (new, or empty),
// all or nothing.
Status write_synth_video(const SynthVideoOptions& options, const ProgressFn& progress = {});

}  // namespace kg
