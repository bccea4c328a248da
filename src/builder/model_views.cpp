#include "builder/model_views.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

#include <opencv2/imgproc.hpp>

namespace kg {

namespace {

constexpr double kPi = 3.14159265358979323846;
// ASIFT's anti-aliasing constant: a shrink by f is preceded by a Gaussian of
// sigma c * sqrt(f^2 - 1) (in the pixels being shrunk).
constexpr double kAntiAlias = 0.8;
// Views whose long edge would fall under this are not rendered: the
// keypoint detector needs a few pixels of margin and several scale levels.
constexpr int kSmallestView = 16;

// The affine map model -> view of one (scale, tilt, longitude), translated
// so that the model rectangle's image starts at (0, 0); `size` its extent.
cv::Matx23d view_map(int width, int height, double scale, double tilt, double longitude,
                     cv::Size& size) {
  const double a = longitude * kPi / 180.0;
  const double c = std::cos(a), s = std::sin(a);
  // Rotate by the longitude, squeeze the rotated y axis by the tilt, scale.
  const cv::Matx22d rotate(c, -s, s, c);
  const cv::Matx22d squeeze(scale, 0.0, 0.0, scale / tilt);
  const cv::Matx22d m = squeeze * rotate;
  double lo_x = 1e300, lo_y = 1e300, hi_x = -1e300, hi_y = -1e300;
  const double corners[4][2] = {
      {-0.5, -0.5}, {width - 0.5, -0.5}, {width - 0.5, height - 0.5}, {-0.5, height - 0.5}};
  for (const auto& p : corners) {
    const double x = m(0, 0) * p[0] + m(0, 1) * p[1], y = m(1, 0) * p[0] + m(1, 1) * p[1];
    lo_x = std::min(lo_x, x), hi_x = std::max(hi_x, x);
    lo_y = std::min(lo_y, y), hi_y = std::max(hi_y, y);
  }
  // The extent rounded up, but not for float noise on an exact size.
  size = cv::Size(static_cast<int>(std::ceil(hi_x - lo_x - 1e-6)),
                  static_cast<int>(std::ceil(hi_y - lo_y - 1e-6)));
  // Pixel centres: the outline's corner -0.5 lands on -0.5.
  return cv::Matx23d(m(0, 0), m(0, 1), -lo_x - 0.5, m(1, 0), m(1, 1), -lo_y - 0.5);
}

void add_pyramid(int width, int height, double tilt, double longitude, const ViewParams& params,
                 std::vector<ModelView>& out) {
  const double long_edge = std::max(width, height);
  const double smallest = params.min_size;
  for (double scale = 1.0;; scale *= params.scale_step) {
    ModelView v;
    v.scale = scale;
    v.tilt = tilt;
    v.longitude = longitude;
    v.to_view = view_map(width, height, scale, tilt, longitude, v.size);
    if (std::max(v.size.width, v.size.height) < kSmallestView) break;
    out.push_back(v);
    if (static_cast<double>(std::max(v.size.width, v.size.height)) <= params.blurred_max_size) {
      ModelView twin = v;
      twin.blur = kBlurredViewSigma;
      out.push_back(twin);
    }
    if (static_cast<double>(std::max(v.size.width, v.size.height)) <= params.glow_max_size) {
      ModelView twin = v;
      twin.glow = true;
      out.push_back(twin);
    }
    // Stop once this view is as small as the smallest sign to be found.
    if (long_edge * scale <= smallest) break;
  }
}

}  // namespace

std::vector<ModelView> model_views(int width, int height, const ViewParams& params,
                                   int legacy_scales) {
  std::vector<ModelView> views;
  if (params.min_size <= 0.f) {
    for (int s = 0; s < legacy_scales; ++s) {
      ModelView v;
      v.scale = std::pow(std::sqrt(0.5), s);
      v.to_view = view_map(width, height, v.scale, 1.0, 0.0, v.size);
      if (v.size.width < 32 || v.size.height < 32) break;
      views.push_back(v);
    }
    return views;
  }
  add_pyramid(width, height, 1.0, 0.0, params, views);
  if (params.max_tilt > 0.f && params.tilt_levels > 0) {
    const double max_t = 1.0 / std::cos(params.max_tilt * kPi / 180.0);
    for (int level = 1; level <= params.tilt_levels; ++level) {
      const double t = 1.0 + (max_t - 1.0) * level / params.tilt_levels;
      const double step = 72.0 / t;
      const int longitudes = std::max(1, static_cast<int>(std::floor(180.0 / step + 1e-9)));
      for (int k = 0; k < longitudes; ++k)
        add_pyramid(width, height, t, 180.0 * k / longitudes, params, views);
    }
  }
  // Views larger than the model image last, so that the model keypoints
  // the other views found (the first to claim a position keeps it) are the
  // same with or without them.
  for (int up = 1;; ++up) {
    const double scale = std::pow(1.0 / params.scale_step, up);
    if (!(scale <= params.max_scale * (1.0 + 1e-3))) break;  // NaN ends it too
    ModelView v;
    v.scale = scale;
    v.to_view = view_map(width, height, scale, 1.0, 0.0, v.size);
    views.push_back(v);
  }
  return views;
}

Status check_view_canvas(int width, int height, const ViewParams& params) {
  const double bound =
      std::max(kViewCanvasFactor * static_cast<double>(width) * height, kMinViewCanvasBound);
  for (const ModelView& v : model_views(width, height, params, 1)) {
    if (v.tilt == 1.0 && v.longitude == 0.0) continue;  // frontal: at most the model's scale
    cv::Size canvas = v.size;
    if (v.longitude != 0.0) {
      cv::Size rotated;
      (void)view_map(width, height, 1.0, 1.0, v.longitude, rotated);
      if (static_cast<double>(rotated.width) * rotated.height >
          static_cast<double>(canvas.width) * canvas.height)
        canvas = rotated;
    }
    if (static_cast<double>(canvas.width) * canvas.height > bound) {
      char angle[32];
      std::snprintf(angle, sizeof(angle), "%.0f", v.longitude);
      return {StatusCode::kInvalidArgument,
              "a " + std::to_string(width) + "x" + std::to_string(height) +
                  " model is too thin for tilted views: the one at longitude " + angle +
                  " degrees would take a " + std::to_string(canvas.width) + "x" +
                  std::to_string(canvas.height) + " canvas, over " +
                  std::to_string(static_cast<long long>(bound)) +
                  " pixels; crop it nearer to square, or build it without tilted views "
                  "(--max-tilt 0)"};
    }
  }
  return Status::ok();
}

int asift_tilt_levels(float max_tilt) {
  if (!(max_tilt > 0.f && max_tilt < 90.f)) return 1;
  const double t = 1.0 / std::cos(max_tilt * kPi / 180.0);
  // At most the 8 levels validate_params accepts (t = 5.8 at 80 degrees).
  return std::clamp(static_cast<int>(std::lround((t - 1.0) / 0.5)), 1, 8);
}

cv::Mat glow_table() {
  cv::Mat table(1, 256, CV_8UC1);
  for (int v = 0; v < 256; ++v) {
    const double y = std::pow(std::min(v / 255.0, kGlowClip) / kGlowClip, kGlowGamma);
    table.at<std::uint8_t>(0, v) = static_cast<std::uint8_t>(std::lround(255.0 * y));
  }
  return table;
}

void render_view(const cv::Mat& gray, const ModelView& view, cv::Mat& out, cv::Mat& inside) {
  const cv::Matx23d& a = view.to_view;
  // Shrink of each model axis direction is at most the largest singular
  // value's inverse; blur in model space by the view's own shrink along
  // each of its axes: the rotated frame's x (scale) and y (scale / tilt).
  const double shrink_x = 1.0 / view.scale, shrink_y = view.tilt / view.scale;
  const double sx = shrink_x > 1.0 ? kAntiAlias * std::sqrt(shrink_x * shrink_x - 1.0) : 0.0;
  const double sy = shrink_y > 1.0 ? kAntiAlias * std::sqrt(shrink_y * shrink_y - 1.0) : 0.0;
  if (view.longitude == 0.0) {
    // A new Mat for the blur: `gray` is the caller's image, never written.
    cv::Mat source = gray;
    if (sx > 0.0 || sy > 0.0) {
      cv::Mat blurred;
      cv::GaussianBlur(gray, blurred, cv::Size(0, 0), std::max(sx, 0.01), std::max(sy, 0.01),
                       cv::BORDER_REPLICATE);
      source = blurred;
    }
    // Enlarged views by cubic interpolation: linear leaves creases at the
    // model's pixel grid, which a fine-scale detector responds to.
    cv::warpAffine(source, out, cv::Mat(a), view.size,
                   view.scale > 1.0 ? cv::INTER_CUBIC : cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  } else {
    // Rotate first (no shrink), blur along the rotated axes, then squeeze.
    cv::Size rotated_size;
    const cv::Matx23d rotate =
        view_map(gray.cols, gray.rows, 1.0, 1.0, view.longitude, rotated_size);
    cv::Mat rotated;
    cv::warpAffine(gray, rotated, cv::Mat(rotate), rotated_size, cv::INTER_LINEAR,
                   cv::BORDER_REPLICATE);
    if (sx > 0.0 || sy > 0.0) {
      cv::GaussianBlur(rotated, rotated, cv::Size(0, 0), std::max(sx, 0.01), std::max(sy, 0.01),
                       cv::BORDER_REPLICATE);
    }
    // view = squeeze(rotated): the rotated image's pixel centres map by
    // diag(scale, scale / tilt) about the -0.5 corner.
    const double kx = view.scale, ky = view.scale / view.tilt;
    const cv::Matx23d squeeze(kx, 0.0, 0.5 * kx - 0.5, 0.0, ky, 0.5 * ky - 0.5);
    cv::warpAffine(rotated, out, cv::Mat(squeeze), view.size, cv::INTER_LINEAR,
                   cv::BORDER_REPLICATE);
  }
  if (view.blur > 0.0)
    cv::GaussianBlur(out, out, cv::Size(0, 0), view.blur, view.blur, cv::BORDER_REPLICATE);
  if (view.glow) cv::LUT(out, glow_table(), out);
  const cv::Mat ones(gray.size(), CV_8UC1, cv::Scalar(255));
  cv::warpAffine(ones, inside, cv::Mat(a), view.size, cv::INTER_NEAREST, cv::BORDER_CONSTANT,
                 cv::Scalar(0));
}

}  // namespace kg
