// The synthetic indoor-sign benchmark on disk: sign images, frames and a
// plain-text manifest with each frame's ground truth.
//
//   DIR/manifest.txt
//   DIR/signs/NN-name.png      the signs (models), BGR
//   DIR/frames/NNNN.png        640x480 BGR frames (--range: any size of the same camera)
//
// manifest.txt, whitespace-separated, one record per line ('#' starts a
// comment line):
//   keygraph-synth 1
//   seed S
//   frame-size W H
//   sign ID NAME FILE WIDTH HEIGHT
//   frame FILE background NAME sign ID corners X0 Y0 X1 Y1 X2 Y2 X3 Y3
//         homography H0..H8 occluded F blur SIGMA motion N noise SIGMA gain G offset O
//         [distance METRES] [jpeg QUALITY]
// A sign-free frame has sign -1 and no corners or homography. Corners are
// the sign's corner pixel centres (clockwise from top-left) in the frame;
// the homography maps sign pixels to frame pixels (row-major). distance
// (range sets, eval/synth/range_frame.h): metres to a 30 cm sign; jpeg: the
// quality of the JPEG round trip the frame went through.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "builder/progress.h"
#include "eval/synth/range_frame.h"
#include "eval/synth/synth_frame.h"
#include "keygraph/status.h"

namespace kg {

struct SynthSetOptions {
  std::string directory;    // created; must not exist or be empty
  std::string backgrounds;  // directory with opencv-doc's photos
  std::uint64_t seed = 1;
  int signs = 50;  // first N of the catalogue
  int frames = 300;
  double sign_free_fraction = 0.2;
  SynthFrameOptions frame;
  // The small-sign benchmark (eval/synth/range_frame.h): when set, frames
  // are rendered by render_range_frame() with these options instead.
  bool range = false;
  RangeFrameOptions range_frame;
};

// The opencv-doc photos used as backgrounds (those present are used).
const std::vector<std::string>& synth_background_names();

struct SynthSign {
  int id = 0;
  std::string name, file;  // file relative to the set's directory
  int width = 0, height = 0;
};

struct SynthFrameEntry {
  std::string file, background;
  SynthFrameInfo info;
};

struct SynthManifest {
  std::uint64_t seed = 0;
  int width = 0, height = 0;
  std::vector<SynthSign> signs;
  std::vector<SynthFrameEntry> frames;
};

// Renders the set, handing each image to `sink` as it is rendered (the
// signs first, then the frames; `file` relative to the set's directory), so
// that memory does not grow with the frames. A sink's error stops it.
using SynthImageSink = std::function<Status(const std::string& file, const cv::Mat& image)>;
Status render_synth_set(const SynthSetOptions& options, SynthManifest& manifest,
                        const SynthImageSink& sink, const ProgressFn& progress = {});
// The same, every image in memory (for tests of small sets).
struct SynthSetImages {
  std::vector<cv::Mat> signs, frames;
};
Status render_synth_set(const SynthSetOptions& options, SynthManifest& manifest,
                        SynthSetImages& images, const ProgressFn& progress = {});

// Whether `directory` can take a new set or video: it does not exist, or is
// an empty directory (never a link, a file or a FIFO), and its parent takes
// files. The error names it.
Status check_new_synth_directory(const std::string& directory);

// Renders and writes the set into options.directory (new, or an empty
// directory), all or nothing (platform/files/output_set.h: the images are
// staged as they are rendered and appear together at the end).
Status write_synth_set(const SynthSetOptions& options, const ProgressFn& progress = {});

// The most a manifest.txt may hold when read (the largest set, 100000
// frames, writes about 40 MB).
inline constexpr std::size_t kMaxSynthManifestBytes = std::size_t{64} << 20;

std::string manifest_text(const SynthManifest& manifest);
// Parses manifest text; errors name the line.
Status parse_manifest(const std::string& text, SynthManifest& out);
Status read_manifest(const std::string& directory, SynthManifest& out);

}  // namespace kg
