#include "eval/synth/synth_frame.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace kg {

namespace {

double uniform(Rng& rng, double lo, double hi) {
  return lo + (hi - lo) * rng.uniform01();
}

cv::Matx33d rotation(double yaw, double pitch, double roll) {
  const double cy = std::cos(yaw), sy = std::sin(yaw), cp = std::cos(pitch), sp = std::sin(pitch),
               cr = std::cos(roll), sr = std::sin(roll);
  const cv::Matx33d ry(cy, 0, sy, 0, 1, 0, -sy, 0, cy);
  const cv::Matx33d rx(1, 0, 0, 0, cp, -sp, 0, sp, cp);
  const cv::Matx33d rz(cr, -sr, 0, sr, cr, 0, 0, 0, 1);
  return rz * rx * ry;
}

}  // namespace

// Lighting that varies linearly across the sign (a lamp to one side).
cv::Mat lit_sign(const cv::Mat& sign, Rng& rng, double& mean_light) {
  const double base = uniform(rng, 0.75, 1.15), slope = uniform(rng, -0.4, 0.4);
  const double angle = uniform(rng, 0, 2 * CV_PI), ca = std::cos(angle), sa = std::sin(angle);
  cv::Mat out(sign.size(), sign.type());
  for (int y = 0; y < sign.rows; ++y) {
    const auto* in = sign.ptr<cv::Vec3b>(y);
    auto* o = out.ptr<cv::Vec3b>(y);
    for (int x = 0; x < sign.cols; ++x) {
      const double t = (x / std::max(1.0, sign.cols - 1.0) - 0.5) * ca +
                       (y / std::max(1.0, sign.rows - 1.0) - 0.5) * sa;
      const double f = std::max(0.2, base + slope * t);
      for (int c = 0; c < 3; ++c) o[x][c] = cv::saturate_cast<std::uint8_t>(in[x][c] * f);
    }
  }
  mean_light = base;
  return out;
}

double occlude(cv::Mat& frame, const cv::Mat& alpha, const cv::Mat& occluder,
               const SynthFrameOptions& options, const Point2f corners[4], Rng& rng,
               OccluderTexture texture_of, const void* context) {
  const double sign_area = cv::sum(alpha)[0];
  if (sign_area < 1 || occluder.empty()) return 0;
  const double target = uniform(rng, 0.05, options.max_occlusion);
  double cx = 0, cy = 0;
  for (int i = 0; i < 4; ++i) {
    cx += corners[i].x / 4;
    cy += corners[i].y / 4;
  }
  const Point2f corner = corners[rng.uniform(4)];
  const double t = uniform(rng, 0.55, 1.05);
  const cv::Point2d centre(cx + t * (corner.x - cx), cy + t * (corner.y - cy));
  // An ellipse of about twice the hidden area (part of it falls outside).
  const double aspect = uniform(rng, 0.35, 1.0);
  const double a = std::sqrt(2.0 * target * sign_area / (CV_PI * aspect)), b = a * aspect;
  cv::Mat mask(frame.size(), CV_8UC1, cv::Scalar(0));
  cv::ellipse(mask, cv::Point(cvRound(centre.x), cvRound(centre.y)),
              cv::Size(std::max(1, cvRound(a)), std::max(1, cvRound(b))), uniform(rng, 0, 180), 0,
              360, cv::Scalar(255), cv::FILLED, cv::LINE_AA);
  const cv::Mat texture = texture_of != nullptr ? texture_of(occluder, frame.size(), rng, context)
                                                : background_view(occluder, frame.size(), rng);
  cv::Mat m;
  mask.convertTo(m, CV_32F, 1.0 / 255);
  double hidden = 0;
  for (int y = 0; y < frame.rows; ++y) {
    const float* w = m.ptr<float>(y);
    const float* s = alpha.ptr<float>(y);
    auto* f = frame.ptr<cv::Vec3b>(y);
    const auto* tx = texture.ptr<cv::Vec3b>(y);
    for (int x = 0; x < frame.cols; ++x) {
      if (w[x] <= 0) continue;
      hidden += double{w[x]} * s[x];
      for (int c = 0; c < 3; ++c)
        f[x][c] = cv::saturate_cast<std::uint8_t>(f[x][c] * (1 - w[x]) + tx[x][c] * w[x]);
    }
  }
  return hidden / sign_area;
}

void sign_outline(cv::Size sign, Point2f out[4]) {
  const auto w = static_cast<float>(sign.width - 1), h = static_cast<float>(sign.height - 1);
  out[0] = {0.f, 0.f};
  out[1] = {w, 0.f};
  out[2] = {w, h};
  out[3] = {0.f, h};
}

cv::Mat background_view(const cv::Mat& photo, cv::Size size, Rng& rng) {
  const double cover = std::max(static_cast<double>(size.width) / photo.cols,
                                static_cast<double>(size.height) / photo.rows);
  const double s = cover * uniform(rng, 1.0, 1.6);
  cv::Mat scaled;
  cv::resize(photo, scaled, cv::Size(), s, s, s < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
  const int w = std::max(size.width, scaled.cols), h = std::max(size.height, scaled.rows);
  if (w != scaled.cols || h != scaled.rows)
    cv::resize(scaled, scaled, cv::Size(w, h), 0, 0, cv::INTER_LINEAR);
  const int x = static_cast<int>(rng.uniform(static_cast<std::uint32_t>(w - size.width + 1)));
  const int y = static_cast<int>(rng.uniform(static_cast<std::uint32_t>(h - size.height + 1)));
  cv::Mat out = scaled(cv::Rect(x, y, size.width, size.height)).clone();
  if (rng.uniform(2) == 1) cv::flip(out, out, 1);
  return out;
}

Homography random_sign_pose(cv::Size sign, const SynthFrameOptions& o, Rng& rng,
                            double* drawn_size) {
  const double deg = CV_PI / 180;
  const cv::Matx33d r = rotation(uniform(rng, -o.max_yaw_deg, o.max_yaw_deg) * deg,
                                 uniform(rng, -o.max_pitch_deg, o.max_pitch_deg) * deg,
                                 uniform(rng, -o.max_roll_deg, o.max_roll_deg) * deg);
  double size = o.log_size ? o.min_size * std::pow(o.max_size / o.min_size, rng.uniform01())
                           : uniform(rng, o.min_size, o.max_size);
  // The rows the sign may take: the frame's, or its central band's.
  const double band = o.band_height > 0 ? std::min<double>(o.band_height, o.height) : o.height;
  const double top = (o.height - band) / 2;
  const double longer = std::max(sign.width, sign.height) - 1.0;
  Point2f outline[4];
  sign_outline(sign, outline);
  cv::Point2d projected[4];
  double min_x = 0, max_x = 0, min_y = 0, max_y = 0;
  for (int attempt = 0; attempt < 40; ++attempt, size *= 0.92) {
    const double depth = o.focal * longer / size;
    min_x = min_y = 1e300;
    max_x = max_y = -1e300;
    for (int i = 0; i < 4; ++i) {
      const cv::Vec3d p = r * cv::Vec3d(outline[i].x - (sign.width - 1) / 2.0,
                                        outline[i].y - (sign.height - 1) / 2.0, 0.0) +
                          cv::Vec3d(0, 0, depth);
      projected[i] = {o.focal * p[0] / p[2], o.focal * p[1] / p[2]};
      min_x = std::min(min_x, projected[i].x);
      max_x = std::max(max_x, projected[i].x);
      min_y = std::min(min_y, projected[i].y);
      max_y = std::max(max_y, projected[i].y);
    }
    if (max_x - min_x <= o.width - 1 - 2 * o.margin && max_y - min_y <= band - 1 - 2 * o.margin)
      break;
  }
  if (drawn_size != nullptr) *drawn_size = size;
  // Anywhere in the frame with every corner inside.
  const double tx =
      uniform(rng, o.margin - min_x, std::max(o.margin - min_x, o.width - 1 - o.margin - max_x));
  const double ty =
      top + uniform(rng, o.margin - min_y, std::max(o.margin - min_y, band - 1 - o.margin - max_y));
  std::vector<cv::Point2f> src, dst;
  for (int i = 0; i < 4; ++i) {
    src.emplace_back(outline[i].x, outline[i].y);
    dst.emplace_back(static_cast<float>(projected[i].x + tx),
                     static_cast<float>(projected[i].y + ty));
  }
  const cv::Mat h = cv::getPerspectiveTransform(src, dst, cv::DECOMP_LU);
  Homography out;
  for (int i = 0; i < 9; ++i)
    out[static_cast<std::size_t>(i)] = h.at<double>(i / 3, i % 3) / h.at<double>(2, 2);
  return out;
}

void composite_sign(cv::Mat& frame, const cv::Mat& sign, const Homography& h, cv::Mat& alpha) {
  const cv::Matx33d m(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]);
  cv::Mat warped, ones(sign.size(), CV_32F, cv::Scalar(1));
  cv::warpPerspective(sign, warped, m, frame.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  cv::warpPerspective(ones, alpha, m, frame.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  // warped is premultiplied: its edge pixels already mix the sign with zeros.
  for (int y = 0; y < frame.rows; ++y) {
    const float* a = alpha.ptr<float>(y);
    const auto* s = warped.ptr<cv::Vec3b>(y);
    auto* f = frame.ptr<cv::Vec3b>(y);
    for (int x = 0; x < frame.cols; ++x) {
      if (a[x] <= 0) continue;
      for (int c = 0; c < 3; ++c)
        f[x][c] = cv::saturate_cast<std::uint8_t>(f[x][c] * (1 - a[x]) + s[x][c]);
    }
  }
}

cv::Mat render_frame(const cv::Mat& background, const cv::Mat& sign, int sign_id,
                     const cv::Mat& occluder, const SynthFrameOptions& options, Rng& rng,
                     SynthFrameInfo& info) {
  info = SynthFrameInfo{};
  cv::Mat frame = background.clone();
  if (!sign.empty()) {
    info.sign = sign_id;
    const cv::Mat lit = lit_sign(sign, rng, info.sign_light);
    info.homography = random_sign_pose(sign.size(), options, rng);
    Point2f outline[4];
    sign_outline(sign.size(), outline);
    for (int i = 0; i < 4; ++i) info.corners[i] = kg::apply(info.homography, outline[i]);
    cv::Mat alpha;
    composite_sign(frame, lit, info.homography, alpha);
    if (rng.uniform01() < options.occlusion_probability)
      info.occluded = occlude(frame, alpha, occluder, options, info.corners, rng);
  }
  degrade_frame(frame, options, rng, info);
  return frame;
}

void degrade_frame(cv::Mat& frame, const SynthFrameOptions& options, Rng& rng,
                   SynthFrameInfo& info) {
  info.gain = uniform(rng, options.min_gain, options.max_gain);
  info.offset = uniform(rng, -20, 20);
  frame.convertTo(frame, -1, info.gain, info.offset);
  const double blur = rng.uniform01();
  if (blur < 0.55) {
    info.blur_sigma = uniform(rng, 0.4, options.max_blur_sigma);
    cv::GaussianBlur(frame, frame, cv::Size(), info.blur_sigma);
  } else if (blur < 0.75) {
    info.motion_blur = 3 + static_cast<int>(rng.uniform(5));
    const double angle = uniform(rng, 0, 180);
    // The recorded length is the reference camera's; the kernel's in frame pixels.
    const int length =
        std::max(3, static_cast<int>(std::lround(info.motion_blur * options.motion_scale)));
    cv::Mat kernel(length, length, CV_32F, cv::Scalar(0));
    const double c = (length - 1) / 2.0, ca = std::cos(angle * CV_PI / 180),
                 sa = std::sin(angle * CV_PI / 180);
    cv::line(kernel, cv::Point(cvRound(c - c * ca), cvRound(c - c * sa)),
             cv::Point(cvRound(c + c * ca), cvRound(c + c * sa)), cv::Scalar(1), 1);
    kernel /= cv::sum(kernel)[0];
    cv::filter2D(frame, frame, -1, kernel);
  }
  info.noise_sigma = uniform(rng, 1.0, options.max_noise_sigma);
  cv::Mat noise(frame.size(), CV_32FC3), noisy;
  cv::RNG cv_rng(rng.next());
  cv_rng.fill(noise, cv::RNG::NORMAL, 0.0, info.noise_sigma);
  frame.convertTo(noisy, CV_32FC3);
  noisy += noise;
  noisy.convertTo(frame, CV_8UC3);
  if (options.jpeg_quality > 0) {
    std::vector<std::uint8_t> bytes;
    cv::imencode(".jpg", frame, bytes, {cv::IMWRITE_JPEG_QUALITY, options.jpeg_quality});
    frame = cv::imdecode(bytes, cv::IMREAD_COLOR);
    info.jpeg_quality = options.jpeg_quality;
  }
}

}  // namespace kg
