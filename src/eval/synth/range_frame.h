// Frames of the small-sign benchmark (keygraph synth --range, issue 38):
// the scene is drawn in a 640x480 reference camera (focal 600 px) and
// rendered at any resolution of the same camera, so that one seed gives the
// same scenes at 640x480 and at 1280x720 with every sign twice as many
// pixels long in the larger frame. The sign is prefiltered to about twice
// its size in the frame before it is warped (a camera integrates light over
// its pixels: a 20 px sign is not an aliased sample of a 480 px drawing),
// and its distance is recorded for a 30 cm sign.
#pragma once

#include <opencv2/core.hpp>

#include "eval/synth/synth_frame.h"

namespace kg {

// The reference camera's frame and focal length, and the sign's size for
// SynthFrameInfo::distance.
inline constexpr int kRangeReferenceWidth = 640, kRangeReferenceHeight = 480;
inline constexpr double kRangeSignMetres = 0.30;

struct RangeFrameOptions {
  SynthFrameOptions frame;        // in reference pixels (width, height 640x480)
  int width = 640, height = 480;  // the rendered frame; scale width / 640
  double scale() const { return static_cast<double>(width) / frame.width; }
};

// The options of `keygraph synth --range` for a frame of width x height:
// signs 20 to 240 px long at 640x480 (0.75 to 9 m), log-uniform, in the
// 16:9 band of the reference frame that a 1280x720 frame shows too.
RangeFrameOptions range_frame_options(int width, int height);

// Checks a frame size for range_frame_options(): the reference frame's
// width scaled, showing at least its 16:9 band and at most all of it.
bool valid_range_frame_size(int width, int height);

// background_view() of the reference frame, drawn with the same random
// choices and rendered at `options`' size (its centre).
cv::Mat range_background(const cv::Mat& photo, const RangeFrameOptions& options, Rng& rng);

// render_frame() for the range benchmark: `photo` is the background photo
// (its view is drawn here), corners and homography in rendered pixels.
cv::Mat render_range_frame(const cv::Mat& photo, const cv::Mat& sign, int sign_id,
                           const cv::Mat& occluder, const RangeFrameOptions& options, Rng& rng,
                           SynthFrameInfo& info);

}  // namespace kg
