// RANSAC's pre-test of two keygraph correspondences: the affine map through
// one's first three points must predict the other's points, a 4-vertex
// circuit's fourth point too.
#include "core/pose/local_affine.h"

#include <gtest/gtest.h>

#include <cmath>

namespace kg {
namespace {

// Scene = A model + t: a rotation by 30 degrees scaled by 0.8, then a shift.
Point2f affine(Point2f m) {
  const float c = 0.8f * std::cos(0.5236f), s = 0.8f * std::sin(0.5236f);
  return {c * m.x - s * m.y + 120.f, s * m.x + c * m.y + 40.f};
}

LocalAffine through(const Point2f (&model)[3]) {
  const Point2f scene[3] = {affine(model[0]), affine(model[1]), affine(model[2])};
  return local_affine(model, scene);
}

TEST(LocalAffine, PredictsPointsOfTheSameMapAndRejectsMovedOnes) {
  const LocalAffine f = through({{10.f, 10.f}, {60.f, 15.f}, {30.f, 70.f}});
  const LocalAffine g = through({{200.f, 40.f}, {240.f, 90.f}, {180.f, 120.f}});
  EXPECT_TRUE(affine_predicts(f, g));
  EXPECT_TRUE(affine_predicts(g, f));
  // A fourth point on the same map, then moved 25 px: beyond the tolerance
  // there (3 px and a quarter of its ~70 px distance from f's centroid: 20 px).
  const Point2f model4{90.f, 50.f};
  EXPECT_TRUE(affine_predicts_point(f, model4, affine(model4)));
  const Point2f moved{affine(model4).x + 25.f, affine(model4).y};
  EXPECT_FALSE(affine_predicts_point(f, model4, moved));
  // One of g's points moved far: f no longer predicts g.
  LocalAffine h = g;
  h.scene[1].y += 120.f;  // the tolerance there is ~70 px (~270 px from f's centroid)
  EXPECT_FALSE(affine_predicts(f, h));
}

TEST(LocalAffine, DegenerateTrianglesPredictNothing) {
  const LocalAffine line = through({{0.f, 0.f}, {10.f, 10.f}, {20.f, 20.f}});
  EXPECT_TRUE(std::isnan(line.a));
  const LocalAffine g = through({{200.f, 40.f}, {240.f, 90.f}, {180.f, 120.f}});
  EXPECT_FALSE(affine_predicts(line, g));
}

}  // namespace
}  // namespace kg
