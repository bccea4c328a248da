#include "eval/synth/synth_video.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <system_error>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "eval/quad_geometry.h"
#include "eval/report_io.h"
#include "eval/synth/sign_catalogue.h"
#include "eval/synth/synth_frame.h"
#include "eval/synth/synth_set.h"
#include "platform/files/output_set.h"
#include "platform/files/regular_file.h"

namespace kg {

namespace fs = std::filesystem;

namespace {

constexpr double kFps = 30;

double uniform(Rng& rng, double lo, double hi) {
  return lo + (hi - lo) * rng.uniform01();
}

// Where the sign is at one instant: its centre in the frame, its longer
// side in pixels were it facing the camera, and its turn in degrees.
struct SignPose {
  double cx = 0, cy = 0, size = 0, yaw = 0, pitch = 0, roll = 0;
};

SignPose mix(const SignPose& a, const SignPose& b, double t) {
  const auto m = [t](double x, double y) { return x + (y - x) * t; };
  return {m(a.cx, b.cx),   m(a.cy, b.cy),       m(a.size, b.size),
          m(a.yaw, b.yaw), m(a.pitch, b.pitch), m(a.roll, b.roll)};
}

struct Key {
  double u;  // time, 0..1 over the sequence
  SignPose pose;
  const char* part;  // the part of the path that ends here
};

// The camera path: key poses joined by smooth steps (the hand starts and
// stops at each), with a little hand shake on top.
class CameraPath {
 public:
  CameraPath(int width, int height, Rng& rng) {
    const double s = width / 640.0;
    const SignPose centre{
        width * uniform(rng, 0.42, 0.58), height * uniform(rng, 0.42, 0.58), 0, 0, 0, 0};
    const double far = width * uniform(rng, 0.075, 0.1), near = width * uniform(rng, 0.36, 0.46);
    mid_ = width * uniform(rng, 0.24, 0.3);
    const auto at = [&](double dx, double dy, double size, double yaw, double pitch, double roll) {
      return SignPose{centre.cx + dx * s, centre.cy + dy * s, size, yaw, pitch, roll};
    };
    const double side = rng.uniform(2) == 0 ? -1 : 1;
    // Approach: from far and turned to near and facing.
    keys_.push_back({0.0,
                     at(uniform(rng, -120, 120), uniform(rng, -60, 60), far, uniform(rng, -30, 30),
                        uniform(rng, -15, 15), uniform(rng, -10, 10)),
                     "approach"});
    keys_.push_back({0.27,
                     at(uniform(rng, -30, 30), uniform(rng, -20, 20), near, uniform(rng, -10, 10),
                        uniform(rng, -8, 8), uniform(rng, -5, 5)),
                     "approach"});
    // Fast pans: back and forth across the frame.
    const double amplitude = uniform(rng, 130, 170);
    for (int k = 0; k < 5; ++k) {
      const double dir = (k % 2 == 0 ? side : -side);
      keys_.push_back({0.31 + 0.04 * k,
                       at(k == 4 ? 0 : dir * amplitude, uniform(rng, -30, 30), mid_,
                          uniform(rng, -12, 12), uniform(rng, -8, 8), uniform(rng, -6, 6)),
                       "pans"});
    }
    // Occlusion: the sign drifts slowly while something passes in front.
    keys_.push_back({0.66,
                     at(uniform(rng, -40, 40), uniform(rng, -20, 20), mid_ * 1.05,
                        uniform(rng, -10, 10), uniform(rng, -8, 8), uniform(rng, -5, 5)),
                     "occlusion"});
    // Leaving the frame to one side, out for a while, and back.
    const double out_x = side < 0 ? -0.75 * mid_ : width + 0.75 * mid_;
    const SignPose gone{out_x, centre.cy, mid_, 0, 0, 0};
    keys_.push_back({0.72, gone, "leave"});
    keys_.push_back({0.77, gone, "leave"});
    keys_.push_back(
        {0.83, at(uniform(rng, -40, 40), uniform(rng, -20, 20), mid_, 0, 0, 0), "leave"});
    // Turns in depth and in plane.
    keys_.push_back({0.88, at(-30, 0, mid_ * 1.1, side * uniform(rng, 30, 40), 0, 5), "turns"});
    keys_.push_back({0.93, at(20, 10, mid_ * 1.1, 0, uniform(rng, 15, 25), side * 30), "turns"});
    keys_.push_back({1.0, at(0, 0, mid_, -side * uniform(rng, 20, 30), 0, -side * 20), "turns"});
    for (double& f : shake_freq_) f = uniform(rng, 1.0, 4.0);
    for (double& p : shake_phase_) p = uniform(rng, 0, 2 * CV_PI);
    shake_ = 1.5 * s;
  }

  // Pose at time u (0..1 over the sequence), seconds t (for the shake).
  SignPose pose(double u, double t) const {
    u = std::clamp(u, 0.0, 1.0);
    std::size_t k = 1;
    while (k + 1 < keys_.size() && keys_[k].u < u) ++k;
    const Key &a = keys_[k - 1], &b = keys_[k];
    const double x = std::clamp((u - a.u) / std::max(1e-9, b.u - a.u), 0.0, 1.0);
    SignPose p = mix(a.pose, b.pose, x * x * (3 - 2 * x));
    p.cx += shake_ * std::sin(2 * CV_PI * shake_freq_[0] * t + shake_phase_[0]);
    p.cy += shake_ * std::sin(2 * CV_PI * shake_freq_[1] * t + shake_phase_[1]);
    p.roll += 0.4 * std::sin(2 * CV_PI * shake_freq_[2] * t + shake_phase_[2]);
    return p;
  }
  const char* part(double u) const {
    for (const Key& k : keys_) {
      if (u <= k.u) return k.part;
    }
    return keys_.back().part;
  }
  // The occluder's horizontal progress across the sign at time u: outside
  // [0, 1] it is out of the way.
  double occluder_progress(double u) const {
    return (u - occlusion_[0]) / (occlusion_[1] - occlusion_[0]);
  }
  double mid_size() const { return mid_; }

 private:
  double mid_ = 0;
  std::vector<Key> keys_;
  double shake_ = 0, shake_freq_[3]{}, shake_phase_[3]{};
  double occlusion_[2] = {0.48, 0.58};  // when the occluder passes, u
};

// The sign's homography (sign pixels -> frame pixels) at `p`: a plane turned
// in 3-D, seen by a pinhole camera (as synth_frame.cpp's random poses).
Homography sign_homography(cv::Size sign, const SignPose& p, int width, int height) {
  const double deg = CV_PI / 180, focal = 600.0 * width / 640;
  const double cy = std::cos(p.yaw * deg), sy = std::sin(p.yaw * deg);
  const double cp = std::cos(p.pitch * deg), sp = std::sin(p.pitch * deg);
  const double cr = std::cos(p.roll * deg), sr = std::sin(p.roll * deg);
  const cv::Matx33d r = cv::Matx33d(cr, -sr, 0, sr, cr, 0, 0, 0, 1) *
                        cv::Matx33d(1, 0, 0, 0, cp, -sp, 0, sp, cp) *
                        cv::Matx33d(cy, 0, sy, 0, 1, 0, -sy, 0, cy);
  const double longer = std::max(sign.width, sign.height) - 1.0;
  const double depth = focal * longer / p.size;
  const cv::Vec3d centre((p.cx - width / 2.0) * depth / focal,
                         (p.cy - height / 2.0) * depth / focal, depth);
  Point2f outline[4];
  sign_outline(sign, outline);
  std::vector<cv::Point2f> src, dst;
  for (const Point2f& o : outline) {
    const cv::Vec3d q =
        r * cv::Vec3d(o.x - (sign.width - 1) / 2.0, o.y - (sign.height - 1) / 2.0, 0.0) + centre;
    src.emplace_back(o.x, o.y);
    dst.emplace_back(static_cast<float>(focal * q[0] / q[2] + width / 2.0),
                     static_cast<float>(focal * q[1] / q[2] + height / 2.0));
  }
  const cv::Mat m = cv::getPerspectiveTransform(src, dst, cv::DECOMP_LU);
  Homography out;
  for (int i = 0; i < 9; ++i)
    out[static_cast<std::size_t>(i)] = m.at<double>(i / 3, i % 3) / m.at<double>(2, 2);
  return out;
}

void corners_of(const Homography& h, cv::Size sign, Point2f out[4]) {
  Point2f outline[4];
  sign_outline(sign, outline);
  for (int c = 0; c < 4; ++c) out[c] = kg::apply(h, outline[c]);
}

// Everything one sequence's frames are drawn from.
struct Scene {
  cv::Mat canvas;      // the background photo, larger than the frame
  cv::Point2d anchor;  // the canvas point at the frame's centre at the start
  cv::Mat sign;        // BGR, lit
  cv::Mat occluder;    // the texture passing in front
  CameraPath path;
  SignPose start;
};

// The occluder's outline in the frame at time u (empty when out of the way).
bool occluder_rect(const Scene& scene, const SignPose& pose, double u, cv::Rect2d& rect) {
  const double p = scene.path.occluder_progress(u);
  if (p < -0.05 || p > 1.05) return false;
  const double s = scene.path.mid_size(), w = 1.3 * s, h = 1.8 * s;
  const double x = pose.cx - (s + w) + p * 2 * (s + w);
  rect = {x - w / 2, pose.cy - h / 2 - 0.1 * s, w, h};
  return true;
}

cv::Mat occluder_mask(cv::Size size, const cv::Rect2d& r) {
  cv::Mat mask(size, CV_8UC1, cv::Scalar(0));
  constexpr int kShift = 4;  // sub-pixel edges
  const auto fx = [](double v) { return static_cast<int>(std::lround(v * (1 << kShift))); };
  const cv::Point pts[4] = {{fx(r.x), fx(r.y)},
                            {fx(r.x + r.width), fx(r.y)},
                            {fx(r.x + r.width), fx(r.y + r.height)},
                            {fx(r.x), fx(r.y + r.height)}};
  cv::fillConvexPoly(mask, pts, 4, cv::Scalar(255), cv::LINE_AA, kShift);
  return mask;
}

// One instant of the scene, BGR 8-bit; `alpha`, `hidden`: the sign's
// coverage and the occluder's mask (0..255), for the visibility.
cv::Mat render_instant(const Scene& scene, double u, double t, cv::Size size, cv::Mat* alpha,
                       cv::Mat* hidden) {
  const SignPose pose = scene.path.pose(u, t);
  // The background is farther than the sign: it moves 0.6 as much, and
  // grows a quarter as fast (in log) as the sign on an approach.
  const double zoom = std::pow(pose.size / scene.start.size, 0.25);
  const double dx = 0.6 * (pose.cx - scene.start.cx), dy = 0.6 * (pose.cy - scene.start.cy);
  const cv::Matx23d m(zoom, 0, size.width / 2.0 + dx - zoom * scene.anchor.x, 0, zoom,
                      size.height / 2.0 + dy - zoom * scene.anchor.y);
  cv::Mat frame;
  cv::warpAffine(scene.canvas, frame, m, size, cv::INTER_LINEAR, cv::BORDER_REFLECT);
  cv::Mat a;
  composite_sign(frame, scene.sign,
                 sign_homography(scene.sign.size(), pose, size.width, size.height), a);
  if (alpha != nullptr) *alpha = a;
  cv::Rect2d r;
  cv::Mat mask;
  if (occluder_rect(scene, pose, u, r)) {
    mask = occluder_mask(size, r);
    // The occluder's texture moves with it.
    const cv::Matx23d mo(1, 0, r.x, 0, 1, r.y);
    cv::Mat texture;
    cv::warpAffine(scene.occluder, texture, mo, size, cv::INTER_LINEAR, cv::BORDER_REFLECT);
    for (int y = 0; y < size.height; ++y) {
      const auto* w = mask.ptr<std::uint8_t>(y);
      auto* f = frame.ptr<cv::Vec3b>(y);
      const auto* tx = texture.ptr<cv::Vec3b>(y);
      for (int x = 0; x < size.width; ++x) {
        if (w[x] == 0) continue;
        const float k = w[x] / 255.f;
        for (int c = 0; c < 3; ++c)
          f[x][c] = cv::saturate_cast<std::uint8_t>(f[x][c] * (1 - k) + tx[x][c] * k);
      }
    }
  }
  if (hidden != nullptr) *hidden = mask;
  return frame;
}

}  // namespace

Status render_synth_video(const SynthVideoOptions& options, SynthVideo& video,
                          const SynthVideoSink& sink, const ProgressFn& progress) {
  if (options.signs < 1 || options.signs > sign_catalogue_size())
    return {StatusCode::kInvalidArgument, "the catalogue has " +
                                              std::to_string(sign_catalogue_size()) +
                                              " signs; asked for " + std::to_string(options.signs)};
  if (options.frames < 30 || options.frames > 100000)
    return {StatusCode::kInvalidArgument, "a video needs 30..100000 frames"};
  if (options.width < 320 || options.height < 240 || options.width > 4096 || options.height > 4096)
    return {StatusCode::kInvalidArgument, "video frames must be 320x240 .. 4096x4096"};
  if (!(options.exposure >= 0 && options.exposure <= 1))
    return {StatusCode::kInvalidArgument, "exposure must be in [0, 1]"};
  std::vector<cv::Mat> photos;
  for (const std::string& name : synth_background_names()) {
    const std::string path = options.backgrounds + "/" + name;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) continue;
    const cv::Mat m = cv::imread(path, cv::IMREAD_COLOR);
    if (!m.empty()) photos.push_back(m);
  }
  if (photos.size() < 2)
    return {StatusCode::kNotFound, options.backgrounds +
                                       ": fewer than 2 of opencv-doc's photos found (install "
                                       "Debian's opencv-doc package)"};
  video = SynthVideo{};
  for (int i = 0; i < options.signs; ++i) {
    SignImage s = render_sign(i, options.seed);
    video.model_names.push_back(s.name);
    video.model_files.push_back("signs/" + s.name + ".png");
    if (Status st = sink(video.model_files.back(), s.image); !st) return st;
  }
  Rng rng(options.seed ^ 0x7669646575ULL);
  video.sign = static_cast<int>(rng.uniform(static_cast<std::uint32_t>(options.signs)));
  video.sign_name = video.model_names[static_cast<std::size_t>(video.sign)];
  const cv::Size size(options.width, options.height);
  const std::size_t b = rng.uniform(static_cast<std::uint32_t>(photos.size()));
  std::size_t o = rng.uniform(static_cast<std::uint32_t>(photos.size() - 1));
  if (o >= b) ++o;
  Scene scene{{}, {}, {}, {}, CameraPath(options.width, options.height, rng), {}};
  scene.start = scene.path.pose(0, 0);
  {
    const cv::Mat& photo = photos[b];
    const double cover = std::max(1.8 * size.width / photo.cols, 1.8 * size.height / photo.rows);
    cv::resize(photo, scene.canvas, cv::Size(), cover, cover,
               cover < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
    scene.anchor = {scene.canvas.cols * uniform(rng, 0.4, 0.6),
                    scene.canvas.rows * uniform(rng, 0.4, 0.6)};
    scene.occluder = background_view(photos[o], size, rng);
    scene.occluder.convertTo(scene.occluder, -1, uniform(rng, 0.5, 0.9), 0);
    const cv::Mat sign = render_sign(video.sign, options.seed).image;
    sign.convertTo(scene.sign, -1, uniform(rng, 0.8, 1.1), 0);
    video.sign_width = sign.cols;
    video.sign_height = sign.rows;
  }
  const double gain_phase = uniform(rng, 0, 2 * CV_PI), noise_sigma = uniform(rng, 1.5, 3.5);
  cv::RNG noise_rng(rng.next());
  const int n = options.frames;
  for (int i = 0; i < n; ++i) {
    const double t = i / kFps, u = static_cast<double>(i) / (n - 1);
    const double half = 0.5 * options.exposure / kFps, du = half * kFps / (n - 1);
    SynthVideoFrame f;
    char name[32];
    std::snprintf(name, sizeof(name), "frames/%04d.jpg", i);
    f.file = name;
    f.part = scene.path.part(u);
    const Homography h =
        sign_homography(scene.sign.size(), scene.path.pose(u, t), size.width, size.height);
    corners_of(h, scene.sign.size(), f.corners);
    // The blur: how far the corners travel while the shutter is open.
    Point2f before[4], after[4];
    corners_of(sign_homography(scene.sign.size(), scene.path.pose(u - du, t - half), size.width,
                               size.height),
               scene.sign.size(), before);
    corners_of(sign_homography(scene.sign.size(), scene.path.pose(u + du, t + half), size.width,
                               size.height),
               scene.sign.size(), after);
    for (int c = 0; c < 4; ++c)
      f.blur_px = std::max(f.blur_px, std::hypot(double{after[c].x} - before[c].x,
                                                 double{after[c].y} - before[c].y));
    // Sub-frames over the exposure, averaged (one per 1.5 px of travel).
    const int subs = std::clamp(static_cast<int>(std::ceil(f.blur_px / 1.5)), 1, 24);
    cv::Mat sum(size, CV_32FC3, cv::Scalar::all(0)), alpha, hidden;
    for (int k = 0; k < subs; ++k) {
      const double s = subs == 1 ? 0.0 : -1.0 + 2.0 * k / (subs - 1);
      cv::Mat instant = render_instant(scene, u + s * du, t + s * half, size, nullptr, nullptr);
      cv::accumulate(instant, sum);
    }
    render_instant(scene, u, t, size, &alpha, &hidden);
    // What shows of the sign at the middle of the exposure.
    const double area = std::abs(signed_area(f.corners));
    double inside = cv::sum(alpha)[0], covered = 0;
    if (!hidden.empty()) {
      cv::Mat h32;
      hidden.convertTo(h32, CV_32F, 1.0 / 255);
      covered = alpha.dot(h32);
    }
    f.visible = area < 1 ? 0 : std::clamp((inside - covered) / area, 0.0, 1.0);
    // Automatic exposure drifting slowly, and sensor noise.
    const double gain = 1.0 + 0.12 * std::sin(2 * CV_PI * 0.15 * t + gain_phase);
    sum.convertTo(sum, -1, gain / subs, 0);
    cv::Mat noise(size, CV_32FC3);
    noise_rng.fill(noise, cv::RNG::NORMAL, 0.0, noise_sigma);
    sum += noise;
    cv::Mat frame;
    sum.convertTo(frame, CV_8UC3);
    if (Status st = sink(f.file, frame); !st) return st;
    video.frames.push_back(f);
    if (progress) progress(i + 1, n, {});
  }
  return Status::ok();
}

std::string synth_video_manifest(const SynthVideoOptions& options, const SynthVideo& video) {
  std::ostringstream out;
  out << "# keygraph synth --video: seed " << options.seed << ", sign " << video.sign_name << ", "
      << video.frames.size() << " frames of " << options.width << "x" << options.height
      << " at 30 fps in order, exposure " << options.exposure
      << " of the frame interval; the sign is an instance where >= " << kVisibleToFind
      << " of it shows, absent where <= " << kVisibleAbsent
      << "; lines without \"instances\" are not scored\n";
  char buf[64];
  std::string part;
  for (const SynthVideoFrame& f : video.frames) {
    if (part != f.part) {  // the parts of the path, for eval --video's breakdown
      part = f.part;
      out << "# part: " << part << '\n';
    }
    out << "{\"scene\": " << json_quote(f.file);
    if (f.visible >= kVisibleToFind) {
      out << ", \"instances\": [{\"model\": " << json_quote(video.sign_name) << ", \"corners\": [";
      for (int c = 0; c < 4; ++c) {
        std::snprintf(buf, sizeof(buf), "%s[%.3f, %.3f]", c ? ", " : "", double{f.corners[c].x},
                      double{f.corners[c].y});
        out << buf;
      }
      out << "]}]";
    } else if (f.visible <= kVisibleAbsent) {
      out << ", \"instances\": []";
    }
    out << "}\n";
  }
  return out.str();
}

Status write_synth_video(const SynthVideoOptions& options, const ProgressFn& progress) {
  if (Status s = check_new_synth_directory(options.directory); !s) return s;
  platform::OutputSet out(options.directory, {});
  const auto stage = [&](const std::string& file, const cv::Mat& image) {
    const std::string path = (fs::path(options.directory) / file).string();
    if (file.size() > 4 && file.compare(file.size() - 4, 4, ".png") == 0)
      return add_png(out, path, image);
    std::vector<std::uint8_t> jpeg;
    if (!cv::imencode(".jpg", image, jpeg, {cv::IMWRITE_JPEG_QUALITY, 95}))
      return Status{StatusCode::kIoError, path + ": JPEG encoding failed"};
    return out.add(path, jpeg.data(), jpeg.size());
  };
  SynthVideo video;
  Status s = render_synth_video(options, video, stage, progress);
  if (s)
    s = out.add((fs::path(options.directory) / "video.jsonl").string(),
                synth_video_manifest(options, video));
  if (s) s = out.commit();
  return s;
}

}  // namespace kg
