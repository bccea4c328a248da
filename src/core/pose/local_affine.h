// The RANSAC pre-test of two keygraph correspondences (keygraph_estimator.h):
// each one's local affine map must predict the other's keypoints. A match's
// map does not depend on the hypothesis it is drawn into, so it is computed
// once per model and frame rather than twice per hypothesis.
#pragma once

#include <cmath>
#include <limits>

#include "keygraph/types.h"

namespace kg {

// Tolerance of the pre-test (affine_predicts): localisation noise plus a fraction of
// the distance over which a local affine map is extrapolated (perspective
// bends it), both in scene pixels.
inline constexpr float kPretestPixels = 3.f;
inline constexpr float kPretestFraction = 0.25f;

// A keygraph correspondence of three keypoint correspondences as the
// pre-test reads it: its points (copied: the test reads them for every
// hypothesis the match is drawn into) and the affine map through them,
// A = S M^-1 from model offsets from model[0] to scene offsets from
// scene[0]. 72 bytes a match (PoseEstimator::match_affine_); a NaN `a`
// marks a degenerate model triangle.
struct LocalAffine {
  Point2f model[3];
  Point2f scene[3];
  float a = 0.f, b = 0.f, c = 0.f, d = 0.f;
  float cx = 0.f, cy = 0.f;  // centroid of scene[0..2]
};

inline LocalAffine local_affine(const Point2f* m0, const Point2f* s0) {
  LocalAffine f;
  for (int j = 0; j < 3; ++j) {
    f.model[j] = m0[j];
    f.scene[j] = s0[j];
  }
  const float m00 = m0[1].x - m0[0].x, m01 = m0[2].x - m0[0].x, m10 = m0[1].y - m0[0].y,
              m11 = m0[2].y - m0[0].y;
  const float det = m00 * m11 - m01 * m10;
  if (!(std::fabs(det) > 1e-3f)) {
    f.a = std::numeric_limits<float>::quiet_NaN();
    return f;
  }
  const float inv = 1.f / det;
  const float s00 = s0[1].x - s0[0].x, s01 = s0[2].x - s0[0].x, s10 = s0[1].y - s0[0].y,
              s11 = s0[2].y - s0[0].y;
  f.a = (s00 * m11 - s01 * m10) * inv;
  f.b = (-s00 * m01 + s01 * m00) * inv;
  f.c = (s10 * m11 - s11 * m10) * inv;
  f.d = (-s10 * m01 + s11 * m00) * inv;
  f.cx = (s0[0].x + s0[1].x + s0[2].x) / 3.f;
  f.cy = (s0[0].y + s0[1].y + s0[2].y) / 3.f;
  return f;
}

// Whether f's (non-degenerate) map predicts `scene` from `model` within the
// pre-test tolerance.
inline bool affine_predicts_point(const LocalAffine& f, Point2f model, Point2f scene) {
  const float dx = model.x - f.model[0].x, dy = model.y - f.model[0].y;
  const float px = f.scene[0].x + f.a * dx + f.b * dy, py = f.scene[0].y + f.c * dx + f.d * dy;
  const float ex = px - scene.x, ey = py - scene.y;
  const float fx = scene.x - f.cx, fy = scene.y - f.cy;
  const float tol = kPretestPixels + kPretestFraction * std::sqrt(fx * fx + fy * fy);
  return !(ex * ex + ey * ey > tol * tol);
}

// Whether f's map predicts the scene points of g's first three model points
// (a 4-vertex circuit's fourth: affine_predicts_point). Degenerate maps fail.
inline bool affine_predicts(const LocalAffine& f, const LocalAffine& g) {
  if (std::isnan(f.a)) return false;
  for (int i = 0; i < 3; ++i)
    if (!affine_predicts_point(f, g.model[i], g.scene[i])) return false;
  return true;
}

}  // namespace kg
