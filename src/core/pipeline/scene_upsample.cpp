// Frames upsampled 2x before detection (KeypointParams::scene_upsample 2,
// or 3 for the frame and its upsampled copy): the pipeline runs on the
// upsampled frame and its results are mapped back to frame pixels here.
// With 4 (coarse to fine) only a window of the frame around the densest
// cluster of correspondences of models that got no pose is upsampled.
#include <algorithm>
#include <cmath>

#include "core/image/upsample.h"
#include "core/pipeline/frame_pipeline.h"
#include "core/pose/confidence.h"
#include "core/pose/overlap.h"

namespace kg {

ImageView FramePipeline::work_frame(ImageView frame) {
  if (!upsampling()) return frame;
  upsample2x(frame, upsampled_);
  return view_of(upsampled_);
}

void FramePipeline::upsample_keypoints(const Keypoint*& keypoints, int& count,
                                       const std::uint8_t*& descriptors) {
  if (count > limits_.max_keypoints) {
    keep_strongest(keypoints, count, descriptors);
    if (descriptors != nullptr) descriptors = detected_descriptors_.data();
  } else {
    detected_.assign(keypoints, keypoints + count);
  }
  for (Keypoint& k : detected_) {
    k.x = to_upsampled(k.x);
    k.y = to_upsampled(k.y);
    k.scale *= 2.f;
  }
  keypoints = detected_.data();
  count = static_cast<int>(detected_.size());
}

void FramePipeline::map_to_frame(DetectionList& out) {
  for (Detection& d : out) {
    d.homography = homography_from_upsampled(d.homography);
    for (Point2f& c : d.corners) c = {from_upsampled(c.x), from_upsampled(c.y)};
    d.rms_error *= 0.5;
    // From the mapped support (the inliers stay those of the upsampled
    // frame's keypoints: the model was fitted on frames as they are).
    d.confidence = detection_confidence(d);
  }
  for (Keypoint& k : scene_keypoints_) {
    k.x = from_upsampled(k.x);
    k.y = from_upsampled(k.y);
    k.scale *= 0.5f;
  }
}

void FramePipeline::merge(const DetectionList& more, DetectionList& out) {
  for (const Detection& d : more) {
    if (!out.push_back(d)) stats_.truncated_detections = true;
  }
  keep_best_of_overlapping(out);
  // Each pass kept up to max_detections; together they may not exceed it.
  // The least supported go first (fewer inliers, then the smaller score
  // over chance, then the later one), in place: no allocation.
  const auto most = static_cast<std::size_t>(limits_.max_detections);
  while (out.size() > most) {
    std::size_t worst = 0;
    for (std::size_t i = 1; i < out.size(); ++i) {
      const Detection& a = out[i];
      const Detection& w = out[worst];
      if (a.inliers < w.inliers ||
          (a.inliers == w.inliers && a.score - a.chance <= w.score - w.chance))
        worst = i;
    }
    for (std::size_t i = worst; i + 1 < out.size(); ++i) out[i] = out[i + 1];
    out.truncate(out.size() - 1);
    stats_.truncated_detections = true;
  }
}

void FramePipeline::drop_weak_upsampled_only(const DetectionList& frame_found,
                                             DetectionList& up) const {
  // An instance the frame's pass found too goes to merge(), which keeps
  // the better of the two; one the upsampled frame alone shows has only
  // that pass's support, which a confidence floor checks (its false
  // detections on the tuning sets were near misses of weak support).
  const double least = options_.upsampled_min_confidence;
  if (!(least > 0.0)) return;
  std::size_t kept = 0;
  for (std::size_t i = 0; i < up.size(); ++i) {
    bool seen = false;
    for (const Detection& d : frame_found)
      seen = seen || outlines_overlap(d.corners, up[i].corners);
    if (seen || up[i].confidence >= least) up[kept++] = up[i];
  }
  up.truncate(kept);
}

namespace {

// scene_upsample 4: the window upsampled, frame pixels (224x224 upsampled:
// a sixth of a 640x480 frame's pixels), and the most correspondences tried
// as its centre (the vote costs this many times the correspondences; no
// allocation). Tuned on the small-sign benchmark (docs/RESULTS.md, "Small
// signs (issue 38)"): windows of 96 to 224 px, one to three of them.
constexpr int kRegion = kUpsampleWindow;
constexpr int kMaxCentres = 256;

bool has_detection(const DetectionList& out, int model) {
  for (const Detection& d : out)
    if (d.model_id == model) return true;
  return false;
}

}  // namespace

Status FramePipeline::upsample_where_it_pays(ImageView frame, DetectionList& out) {
  // Each correspondence of a model without a pose whose scene vertices fit
  // in half the window votes at their centre; the window goes where the
  // most votes fall within a quarter of it either way.
  const auto region = static_cast<float>(kRegion);
  const int n = static_cast<int>(matches_.size());
  const int vertices = static_cast<int>(params_.graph.structure);
  const auto centre_of = [&](const KeygraphMatch& m, Point2f& c) {
    float x = 0, y = 0, lo_x = 1e30f, hi_x = -1e30f, lo_y = 1e30f, hi_y = -1e30f;
    for (int v = 0; v < vertices; ++v) {
      const Point2f& p = scene_points_[static_cast<std::size_t>(m.scene_vertices[v])];
      x += p.x;
      y += p.y;
      lo_x = std::min(lo_x, p.x);
      hi_x = std::max(hi_x, p.x);
      lo_y = std::min(lo_y, p.y);
      hi_y = std::max(hi_y, p.y);
    }
    c = {x / static_cast<float>(vertices), y / static_cast<float>(vertices)};
    return hi_x - lo_x <= region / 2 && hi_y - lo_y <= region / 2 &&
           !has_detection(out, m.model_id);
  };
  int best_votes = 0;
  Point2f best{};
  const int step = std::max(1, n / kMaxCentres);
  for (int i = 0; i < n; i += step) {
    Point2f c;
    if (!centre_of(matches_[static_cast<std::size_t>(i)], c)) continue;
    int votes = 0;
    for (int j = 0; j < n; ++j) {
      Point2f d;
      if (centre_of(matches_[static_cast<std::size_t>(j)], d) &&
          std::abs(d.x - c.x) <= region / 4 && std::abs(d.y - c.y) <= region / 4)
        ++votes;
    }
    if (votes > best_votes) {
      best_votes = votes;
      best = c;
    }
  }
  // As many correspondences as a pose needs, or nothing worth a second look.
  if (best_votes < params_.ransac.min_inlier_keygraphs) return Status::ok();
  const int w = std::min(kRegion, frame.width), h = std::min(kRegion, frame.height);
  const int x0 = std::clamp(static_cast<int>(std::lround(best.x)) - w / 2, 0, frame.width - w);
  const int y0 = std::clamp(static_cast<int>(std::lround(best.y)) - h / 2, 0, frame.height - h);
  upsample2x(ImageView(frame.row(y0) + x0, w, h, frame.stride), upsampled_);
  upsampled_found_.clear();
  const Status s = detect_keypoints_and_run(view_of(upsampled_), upsampled_found_);
  // map_to_frame() leaves the window's pixels: moved into the frame's.
  map_to_frame(upsampled_found_);
  for (Detection& d : upsampled_found_) {
    Homography& m = d.homography;  // [1 0 x0; 0 1 y0; 0 0 1] H
    for (std::size_t c = 0; c < 3; ++c) {
      m[c] += x0 * m[6 + c];
      m[3 + c] += y0 * m[6 + c];
    }
    for (Point2f& c : d.corners) c = {c.x + static_cast<float>(x0), c.y + static_cast<float>(y0)};
  }
  for (Keypoint& k : scene_keypoints_) {
    k.x += static_cast<float>(x0);
    k.y += static_cast<float>(y0);
  }
  merge(upsampled_found_, out);
  return s;
}

}  // namespace kg
