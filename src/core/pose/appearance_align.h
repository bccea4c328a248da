// Photometric refinement of a found pose: the model's stored appearance
// image (format 6.2, section 15) is aligned onto the frame by inverse
// compositional Gauss-Newton on the homography (Baker & Matthews, "Lucas-
// Kanade 20 years on"), with gain and bias projected out of the steepest-
// descent images so that lighting changes do not bias the pose. Keypoint
// correspondences bring the pose within a few pixels; the image brings it
// to a fraction of one, and the normalised cross-correlation of the aligned
// image with the frame is a check of the model's identity that no keypoint
// count gives (two signs differing only by an arrow's direction share most
// keypoints, not most pixels).
//
// Coarse to fine: the appearance at half resolution first, then at full.
// The work per detection is a few hundred thousand multiply-adds; the
// buffers are reserved once (reserve()) and align() allocates nothing.
#pragma once

#include <cstdint>

#include "core/support/worker_pool.h"
#include "core/support/workspace.h"
#include "keygraph/image.h"
#include "keygraph/types.h"

namespace kg {

// An appearance image and where it lies in model pixels: pixel (u, v)
// covers model pixels [u / scale_x, (u + 1) / scale_x) x
// [v / scale_y, (v + 1) / scale_y) (area resampling to a given size).
struct AppearanceImage {
  const std::uint8_t* pixels = nullptr;  // width * height bytes, row-major
  int width = 0;
  int height = 0;
  float scale_x = 0.f;  // appearance pixels per model pixel, each axis
  float scale_y = 0.f;
};

struct AppearanceFit {
  // Whether the correlation could be measured: false when under 70 % of the
  // appearance falls inside the frame, the appearance is flat or too small
  // (under 64 interior pixels), or the pose is degenerate.
  bool measured = false;
  bool aligned = false;  // the refined pose was kept (it correlates better)
  // Normalised cross-correlation of the appearance with the frame under the
  // pose given and under the pose returned (when measured), scored at the
  // appearance's level closest to the frame's resolution.
  double ncc_before = 0.0;
  double ncc = 0.0;
  int iterations = 0;  // Gauss-Newton steps over both levels
  // The correlation of the coarse (half) level's selected pixels with the
  // frame at its last Gauss-Newton step (coarse_measured: whether it ran).
  bool coarse_measured = false;
  double ncc_coarse = 0.0;
  // No step or only the coarse level's were run: the correlation under the
  // pose given was below align()'s refuse_below (coarse_measured false), or
  // it and the coarse level's were both below abandon_below. The pose is
  // then returned unchanged (aligned false, ncc = ncc_before).
  bool abandoned = false;
};

class AppearanceAligner {
 public:
  explicit AppearanceAligner(std::pmr::memory_resource* memory = std::pmr::get_default_resource());
  // Sizes the buffers for appearance images of up to max_pixels pixels.
  void reserve(int max_pixels);

  // Refines h (model pixels -> frame pixels) by aligning `appearance` to
  // `frame` (best a lightly blurred frame: the appearance is area-averaged),
  // and keeps the refinement only when it raises the correlation. An
  // appearance larger than reserved is not aligned (measured stays false).
  // The fine level is skipped (AppearanceFit::abandoned) when, after the
  // coarse level's steps, neither the pose given nor the coarse level
  // correlates at abandon_below or more, and every step when the pose given
  // correlates under refuse_below: poses that will be rejected for their
  // appearance either way (the defaults never abandon).
  AppearanceFit align(const AppearanceImage& appearance, ImageView frame, Homography& h,
                      double abandon_below = -2.0, double refuse_below = -2.0);

  // Workers (nullptr: none) to sample the frame under the pose with: each
  // pixel's sample is computed on its own, so the fit is the same, bit for
  // bit, with or without them. Not while the pool runs another task.
  void set_workers(WorkerPool* workers) { workers_ = workers; }

 private:
  struct Level {
    const float* values = nullptr;
    int width = 0, height = 0;
    float scale_x = 0.f, scale_y = 0.f;
  };
  // Smooths the appearance into full_; false when it cannot be used.
  bool prepare(const AppearanceImage& appearance, ImageView frame);
  // Runs Gauss-Newton on one level; g maps the level's normalised
  // coordinates to frame pixels and is updated in place. With `ncc`, the
  // correlation of the selected pixels with the frame sampled at the last
  // step (false when no step sampled the frame or it cannot be measured).
  int refine_level(const Level& level, ImageView frame, double g[9], double* ncc = nullptr,
                   bool* ncc_measured = nullptr);
  // NCC of the level with the frame under g (AppearanceFit::measured says
  // when it cannot be measured).
  bool correlation(const Level& level, ImageView frame, const double g[9], double& ncc);
  // Frame pixels per level pixel at the level's centre under g.
  static double footprint(const Level& level, const double g[9]);
  // Samples the frame under g at the listed pixels of the level (into
  // warped_ and valid_, indexed by pixel).
  void warp_level(const Level& level, ImageView frame, const double g[9],
                  const std::uint32_t* pixels, std::size_t count);

  WorkerPool* workers_ = nullptr;

  WorkVector<float> full_;              // the appearance, lightly smoothed
  WorkVector<float> half_;              // the same at half resolution
  WorkVector<float> steepest_;          // 8 steepest-descent images, pixel-major
  WorkVector<float> warped_;            // the frame sampled under the pose
  WorkVector<std::uint8_t> valid_;      // 1 where the sample fell inside the frame
  WorkVector<float> magnitude_;         // gradient magnitudes, for the selection
  WorkVector<std::uint32_t> selected_;  // pixels the Gauss-Newton steps use
  WorkVector<std::uint32_t> interior_;  // every pixel but the border
};

}  // namespace kg
