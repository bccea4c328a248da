// One frame of the synthetic sign benchmark: a view of a real photo as the
// background, a sign composited under a random homography (a plane turned
// in 3-D and seen by a pinhole camera), with uneven lighting across the
// sign, partial occlusion, a global illumination change, blur and sensor
// noise. Every random choice comes from the Rng passed in, so a frame is a
// function of its seed.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "core/support/rng.h"
#include "keygraph/types.h"

namespace kg {

struct SynthFrameOptions {
  int width = 640, height = 480;
  // Longer side of the sign in the frame before foreshortening, pixels.
  double min_size = 100, max_size = 320;
  double max_yaw_deg = 50, max_pitch_deg = 35, max_roll_deg = 15;
  double focal = 600;  // pixels (about a 56 degree horizontal field at 640 wide)
  int margin = 4;      // the sign's corners stay this far inside the frame
  double occlusion_probability = 0.35;
  double max_occlusion = 0.3;  // fraction of the sign's area
  double max_blur_sigma = 1.6;
  double max_noise_sigma = 6;
  double min_gain = 0.6, max_gain = 1.25;  // global illumination
  // The size drawn log-uniformly between min_size and max_size (as many
  // signs per octave of size, or of distance), not uniformly.
  bool log_size = false;
  // > 0: the sign's corners stay inside the central band of this many rows
  // (the part of a 640x480 view that a 16:9 frame of the same camera shows).
  double band_height = 0;
  // Motion blur's length is multiplied by this (an angular motion covers
  // more pixels in a frame of a finer camera).
  double motion_scale = 1;
  int jpeg_quality = 0;  // > 0: the frame goes through JPEG at this quality
};

// What was drawn into a frame.
struct SynthFrameInfo {
  int sign = -1;            // -1: no sign
  Homography homography{};  // sign pixels -> frame pixels
  Point2f corners[4];       // sign outline (pixel centres, clockwise from top-left) in the frame
  double occluded = 0;      // fraction of the sign's pixels hidden
  double blur_sigma = 0;    // Gaussian blur (0: none)
  int motion_blur = 0;      // motion blur length in pixels (0: none)
  double noise_sigma = 0;   // gray levels
  double gain = 1, offset = 0;  // frame = frame * gain + offset
  double sign_light = 1;        // mean lighting factor across the sign
  double distance = 0;          // metres to a 30 cm sign (0: not recorded)
  int jpeg_quality = 0;         // the JPEG round trip's quality (0: none)
};

// The sign's outline: pixel centres of its corners, clockwise from top-left.
void sign_outline(cv::Size sign, Point2f out[4]);

// A random view of `photo` at `size`: scaled to cover it (and up to 1.6x
// more), cropped at random, mirrored half of the time.
cv::Mat background_view(const cv::Mat& photo, cv::Size size, Rng& rng);

// A random pose of a sign of `sign` size with every corner inside the frame
// (and the band). `drawn_size`, when given, receives the longer side the
// sign was given before foreshortening (after any shrinking to fit), px.
Homography random_sign_pose(cv::Size sign, const SynthFrameOptions& options, Rng& rng,
                            double* drawn_size = nullptr);

// The sign lit unevenly (a lamp to one side); its mean lighting factor.
cv::Mat lit_sign(const cv::Mat& sign, Rng& rng, double& mean_light);

// Hides part of the sign (coverage `alpha`) behind an ellipse textured by
// `texture` (called once, with the Rng, for a frame-sized image); returns
// the hidden fraction of the sign.
using OccluderTexture = cv::Mat (*)(const cv::Mat& photo, cv::Size size, Rng& rng,
                                    const void* context);
double occlude(cv::Mat& frame, const cv::Mat& alpha, const cv::Mat& occluder,
               const SynthFrameOptions& options, const Point2f corners[4], Rng& rng,
               OccluderTexture texture = nullptr, const void* context = nullptr);

// Illumination change, blur or motion blur, sensor noise and the JPEG
// round trip of a rendered frame (the last steps of render_frame()).
void degrade_frame(cv::Mat& frame, const SynthFrameOptions& options, Rng& rng,
                   SynthFrameInfo& info);

// Warps `sign` (BGR) into `frame` (BGR) under h; `alpha` receives the
// sign's coverage of each frame pixel (CV_32F, 0..1).
void composite_sign(cv::Mat& frame, const cv::Mat& sign, const Homography& h, cv::Mat& alpha);

// Renders a frame: `sign` may be empty (a sign-free frame); `occluder` is
// a photo whose texture hides part of the sign.
cv::Mat render_frame(const cv::Mat& background, const cv::Mat& sign, int sign_id,
                     const cv::Mat& occluder, const SynthFrameOptions& options, Rng& rng,
                     SynthFrameInfo& info);

}  // namespace kg
