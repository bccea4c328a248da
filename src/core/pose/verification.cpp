#include "core/pose/verification.h"

#include <algorithm>
#include <cmath>

#include "core/index/index_format.h"

namespace kg {

int pose_view_code(const Homography& h, const ModelInfo& info) {
  const Point2f c{0.5f * (info.width - 1.f), 0.5f * (info.height - 1.f)};
  const Point2f o = kg::apply(h, c), x = kg::apply(h, {c.x + 1.f, c.y}),
                y = kg::apply(h, {c.x, c.y + 1.f});
  const double det = std::fabs(double{x.x - o.x} * (y.y - o.y) - double{x.y - o.y} * (y.x - o.x));
  if (!(det > 0.0) || !std::isfinite(det)) return 0;
  const double code = std::round(-0.5 * std::log2(det) * format::kViewCodesPerOctave);
  return static_cast<int>(std::clamp(code, 0.0, 255.0));
}

float verification_radius(const RansacParams& rp, int code) {
  const double scale = std::exp2(-code / static_cast<double>(format::kViewCodesPerOctave));
  return static_cast<float>(rp.inlier_threshold * std::clamp(std::sqrt(scale), 0.5, 1.0));
}

double chance_fraction(const ModelIndex& index, const RansacParams& rp, const ModelInfo& info,
                       const FrameKeypoints& frame, const Homography& h) {
  // The same count under the pose shifted in the scene by a few inlier
  // thresholds: how often model keypoints land on frame keypoints by chance
  // in this part of the frame.
  const auto shift = static_cast<float>(3.0 * rp.inlier_threshold);
  const Point2f offsets[4] = {{shift, 0.f}, {-shift, 0.f}, {0.f, shift}, {0.f, -shift}};
  int inside = 0, hits = 0;
  for (const Point2f& o : offsets) {
    for_each_shown_keypoint(index, rp, info, frame, h, o, [&](std::uint32_t, Point2f p, float r) {
      ++inside;
      hits += frame.grid->nearest(p, r) >= 0 ? 1 : 0;
    });
  }
  return inside > 0 ? static_cast<double>(hits) / inside : 0.0;
}

double support_z(double fraction, double chance, int shown) {
  const double spread = std::sqrt(std::max(1e-9, shown * chance * (1.0 - chance)));
  return (fraction - chance) * shown / spread;
}

PoseSupport measure_pose_support(const ModelIndex& index, int model_id, const FrameKeypoints& frame,
                                 const Homography& h) {
  return measure_pose_support(index, index.params().ransac, model_id, frame, h);
}

PoseSupport measure_pose_support(const ModelIndex& index, const RansacParams& rp, int model_id,
                                 const FrameKeypoints& frame, const Homography& h) {
  PoseSupport support;
  if (model_id < 0 || model_id >= index.model_count() || frame.grid == nullptr) return support;
  const ModelInfo info = index.model(model_id);
  for_each_shown_keypoint(index, rp, info, frame, h, {0.f, 0.f},
                          [&](std::uint32_t, Point2f p, float radius) {
                            ++support.shown;
                            support.refound += frame.grid->nearest(p, radius) >= 0 ? 1 : 0;
                          });
  if (support.shown == 0) return support;
  support.chance = chance_fraction(index, rp, info, frame, h);
  support.z = support_z(static_cast<double>(support.refound) / support.shown, support.chance,
                        support.shown);
  return support;
}

}  // namespace kg
