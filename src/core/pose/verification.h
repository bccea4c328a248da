// The keypoint verification of a pose (not in the paper): under a pose,
// the model keypoints its scale shows inside the frame, how many land near
// a frame keypoint, and how many would by chance (the pose shifted by three
// inlier thresholds). The detector accepts a pose only when the first
// fraction beats chance by RansacParams::min_verification_z binomial
// standard deviations; the guided refinement pairs the same keypoints.
#pragma once

#include <cmath>
#include <cstdint>

#include "core/pose/point_grid.h"
#include "keygraph/image.h"
#include "keygraph/model_index.h"
#include "keygraph/params.h"
#include "keygraph/types.h"

namespace kg {

// All keypoints of the frame (before sampling), for guided refinement: once
// a pose is found, every model keypoint is projected and paired with the
// nearest frame keypoint within the inlier threshold; the pose is refined on
// those pairs and the fraction of model keypoints so re-found is the
// detection's score.
struct FrameKeypoints {
  const Keypoint* keypoints = nullptr;
  int count = 0;
  const PointGrid* grid = nullptr;
  int width = 0;
  int height = 0;
  // The frame, lightly blurred, for the photometric refinement (empty: none).
  ImageView image;
};

// The keypoint support of a pose, as the detector's verification measures
// it: the model keypoints the pose's scale shows inside the frame, those
// that land within the verification radius of a frame keypoint, the
// fraction that lands so under the pose shifted by three inlier thresholds
// (chance), and the binomial z-score of the first fraction against it. A
// detection needs z >= ransac.min_verification_z. For evaluation: asked of
// a ground-truth pose, it says whether the frame's keypoints could have
// confirmed it at all (`keygraph eval --truth`).
struct PoseSupport {
  int shown = 0;
  int refound = 0;
  double chance = 0.0;
  double z = 0.0;
};
// With the index's RANSAC parameters, or with `rp` (a detector's options).
PoseSupport measure_pose_support(const ModelIndex& index, int model_id, const FrameKeypoints& frame,
                                 const Homography& h);
PoseSupport measure_pose_support(const ModelIndex& index, const RansacParams& rp, int model_id,
                                 const FrameKeypoints& frame, const Homography& h);

// View scale code (core/index/index_format.h) of a pose: the area scale of its
// local affine map at the model's centre, clamped to the codes' range (a
// scene larger than the model image is coded as the model's own scale).
int pose_view_code(const Homography& h, const ModelInfo& info);

// Radius of the guided matching and the verification: the inlier
// threshold, shrunk for instances smaller than the model image (down to
// half of it at a quarter of the model's size). Keypoints of a small
// instance are fine-scale ones, localised to a pixel or two, while the
// chance of a hit grows with the radius squared: the full radius there
// lets chance hits swamp the verification.
float verification_radius(const RansacParams& rp, int code);

// Whether the views detected model keypoint i near the scale of the pose
// (within half an octave of its finest or coarsest view): keypoints of
// fine detail do not exist in a small instance and only dilute the
// verification.
inline bool seen_at(const std::uint8_t* views, std::uint32_t i, int code) {
  constexpr int kMargin = 4;  // eighths of an octave
  return code >= views[2 * i] - kMargin && code <= views[2 * i + 1] + kMargin;
}

// Calls visit(i, p) for each model keypoint i that the pose's scale shows
// (seen_at) and that lands at p inside the frame under h, shifted by
// `offset` scene pixels, with the verification radius at that scale.
template <class Visit>
void for_each_shown_keypoint(const ModelIndex& index, const RansacParams& rp, const ModelInfo& info,
                             const FrameKeypoints& frame, const Homography& h, Point2f offset,
                             Visit&& visit) {
  const Point2f* model_points = index.keypoints() + info.keypoint_begin;
  const std::uint8_t* views = index.keypoint_views() + 2 * std::size_t{info.keypoint_begin};
  const int code = pose_view_code(h, info);
  const float radius = verification_radius(rp, code);
  for (std::uint32_t i = 0; i < info.keypoint_count; ++i) {
    if (!seen_at(views, i, code)) continue;
    Point2f p = kg::apply(h, model_points[i]);
    p.x += offset.x;
    p.y += offset.y;
    if (!(p.x >= 0.f && p.y >= 0.f && p.x <= static_cast<float>(frame.width - 1) &&
          p.y <= static_cast<float>(frame.height - 1)))
      continue;
    visit(i, p, radius);
  }
}

// The fraction of the shown model keypoints that land near a frame keypoint
// under h shifted by three inlier thresholds (four directions): chance.
double chance_fraction(const ModelIndex& index, const RansacParams& rp, const ModelInfo& info,
                       const FrameKeypoints& frame, const Homography& h);
// Binomial z-score of the fraction of `shown` model keypoints re-found
// against the fraction chance gives.
double support_z(double fraction, double chance, int shown);

}  // namespace kg
