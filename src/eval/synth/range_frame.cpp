#include "eval/synth/range_frame.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "eval/quad_geometry.h"

namespace kg {

namespace {

// Pixel-centre scaling: continuous coordinates scaled by f, then moved.
cv::Matx33d scaling(double fx, double fy, double tx = 0, double ty = 0) {
  return {fx, 0, 0.5 * fx - 0.5 + tx, 0, fy, 0.5 * fy - 0.5 + ty, 0, 0, 1};
}

// Reference pixels -> rendered pixels (the reference frame's centred window).
cv::Matx33d reference_to_frame(const RangeFrameOptions& o) {
  const double s = o.scale(), shown = o.height / s;
  const double top = (o.frame.height - shown) / 2;  // reference rows above the window
  return scaling(s, s, 0, -top * s);
}

cv::Mat texture_of(const cv::Mat& photo, cv::Size, Rng& rng, const void* context) {
  return range_background(photo, *static_cast<const RangeFrameOptions*>(context), rng);
}

}  // namespace

RangeFrameOptions range_frame_options(int width, int height) {
  RangeFrameOptions o;
  o.frame.width = kRangeReferenceWidth;
  o.frame.height = kRangeReferenceHeight;
  o.frame.min_size = 20;
  o.frame.max_size = 240;
  o.frame.log_size = true;
  o.frame.band_height = kRangeReferenceWidth * 9.0 / 16;
  o.width = width;
  o.height = height;
  o.frame.motion_scale = o.scale();
  return o;
}

bool valid_range_frame_size(int width, int height) {
  if (width < 64 || height < 64 || width > 8192 || height > 8192) return false;
  const double shown = height * static_cast<double>(kRangeReferenceWidth) / width;
  return shown >= kRangeReferenceWidth * 9.0 / 16 - 1e-9 && shown <= kRangeReferenceHeight + 1e-9;
}

cv::Mat range_background(const cv::Mat& photo, const RangeFrameOptions& o, Rng& rng) {
  // background_view()'s draws at the reference size.
  const cv::Size ref(o.frame.width, o.frame.height);
  const double cover = std::max(static_cast<double>(ref.width) / photo.cols,
                                static_cast<double>(ref.height) / photo.rows);
  const double s = cover * (1.0 + 0.6 * rng.uniform01());
  const int w = std::max(ref.width, static_cast<int>(std::lround(photo.cols * s)));
  const int h = std::max(ref.height, static_cast<int>(std::lround(photo.rows * s)));
  const double x = rng.uniform(static_cast<std::uint32_t>(w - ref.width + 1));
  const double y = rng.uniform(static_cast<std::uint32_t>(h - ref.height + 1));
  const bool flip = rng.uniform(2) == 1;
  // Photo pixels -> the scaled photo -> the cropped (and mirrored) view ->
  // the rendered frame.
  const double sx = static_cast<double>(w) / photo.cols, sy = static_cast<double>(h) / photo.rows;
  const cv::Matx33d crop(1, 0, -x, 0, 1, -y, 0, 0, 1);
  const cv::Matx33d mirror =
      flip ? cv::Matx33d(-1, 0, ref.width - 1.0, 0, 1, 0, 0, 0, 1) : cv::Matx33d::eye();
  cv::Matx33d to_frame = reference_to_frame(o) * mirror * crop * scaling(sx, sy);
  cv::Mat source = photo;
  const double shrink_x = sx * o.scale(), shrink_y = sy * o.scale();
  if (shrink_x < 1 || shrink_y < 1) {  // area-average first: no aliasing
    const double fx = std::min(1.0, shrink_x), fy = std::min(1.0, shrink_y);
    cv::resize(photo, source, cv::Size(), fx, fy, cv::INTER_AREA);
    const cv::Matx33d to_source = scaling(static_cast<double>(source.cols) / photo.cols,
                                          static_cast<double>(source.rows) / photo.rows);
    to_frame = to_frame * to_source.inv();
  }
  const cv::Matx23d affine(to_frame(0, 0), to_frame(0, 1), to_frame(0, 2), to_frame(1, 0),
                           to_frame(1, 1), to_frame(1, 2));
  cv::Mat out;
  cv::warpAffine(source, out, affine, cv::Size(o.width, o.height), cv::INTER_LINEAR,
                 cv::BORDER_REFLECT);
  return out;
}

cv::Mat render_range_frame(const cv::Mat& photo, const cv::Mat& sign, int sign_id,
                           const cv::Mat& occluder, const RangeFrameOptions& options, Rng& rng,
                           SynthFrameInfo& info) {
  info = SynthFrameInfo{};
  cv::Mat frame = range_background(photo, options, rng);
  if (!sign.empty()) {
    info.sign = sign_id;
    const cv::Mat lit = lit_sign(sign, rng, info.sign_light);
    double size = 0;
    const Homography pose = random_sign_pose(sign.size(), options.frame, rng, &size);
    info.distance = options.frame.focal * kRangeSignMetres / size;
    const cv::Matx33d h =
        reference_to_frame(options) * cv::Matx33d(pose[0], pose[1], pose[2], pose[3], pose[4],
                                                  pose[5], pose[6], pose[7], pose[8]);
    for (int i = 0; i < 9; ++i) info.homography[static_cast<std::size_t>(i)] = h.val[i] / h.val[8];
    Point2f outline[4];
    sign_outline(sign.size(), outline);
    for (int i = 0; i < 4; ++i) info.corners[i] = kg::apply(info.homography, outline[i]);
    // The sign area-averaged down to about twice its size in the frame.
    const double longer = std::max(sign.cols, sign.rows);
    const double k = std::min(1.0, 2 * longest_side(info.corners) / longer);
    cv::Mat drawn = lit;
    cv::Matx33d to_sign = cv::Matx33d::eye();
    if (k < 1) {
      cv::resize(lit, drawn,
                 cv::Size(std::max(2, static_cast<int>(std::lround(lit.cols * k))),
                          std::max(2, static_cast<int>(std::lround(lit.rows * k)))),
                 0, 0, cv::INTER_AREA);
      to_sign = scaling(static_cast<double>(drawn.cols) / lit.cols,
                        static_cast<double>(drawn.rows) / lit.rows)
                    .inv();
    }
    const cv::Matx33d hd = h * to_sign;
    Homography drawn_pose;
    for (int i = 0; i < 9; ++i) drawn_pose[static_cast<std::size_t>(i)] = hd.val[i] / hd.val[8];
    cv::Mat alpha;
    composite_sign(frame, drawn, drawn_pose, alpha);
    if (rng.uniform01() < options.frame.occlusion_probability)
      info.occluded =
          occlude(frame, alpha, occluder, options.frame, info.corners, rng, texture_of, &options);
  }
  degrade_frame(frame, options.frame, rng, info);
  return frame;
}

}  // namespace kg
