// Overlapping detections (core/pose/pose.h): a second instance of one model on
// the same sign, and look-alike models on one sign, keep the best
// supported detection; detections elsewhere are untouched.
#include <gtest/gtest.h>

#include "core/pose/pose.h"
#include "keygraph/detector.h"

namespace kg {
namespace {

Detection at(int model, float x, float y, float size, int inliers, double score = 0.5,
             double chance = 0.1) {
  Detection d;
  d.model_id = model;
  d.corners[0] = {x, y};
  d.corners[1] = {x + size, y};
  d.corners[2] = {x + size, y + size};
  d.corners[3] = {x, y + size};
  d.inliers = inliers;
  d.score = score;
  d.chance = chance;
  return d;
}

TEST(Overlap, CentreInsideEitherOutline) {
  const Detection big = at(0, 0, 0, 100, 10), small = at(1, 40, 40, 10, 10);
  const Detection apart = at(2, 200, 0, 100, 10), edge = at(3, 60, 0, 100, 10);
  EXPECT_TRUE(outlines_overlap(big.corners, small.corners));  // small's centre inside big
  EXPECT_TRUE(outlines_overlap(small.corners, big.corners));
  EXPECT_FALSE(outlines_overlap(big.corners, apart.corners));
  // Overlapping by 40 %, but neither centre inside the other: two signs side by side.
  EXPECT_FALSE(outlines_overlap(big.corners, edge.corners));
  // Either orientation of the outline.
  Detection reversed = big;
  std::swap(reversed.corners[1], reversed.corners[3]);
  EXPECT_TRUE(outlines_overlap(reversed.corners, small.corners));
}

TEST(Overlap, KeepsTheBestSupportedOfEachGroup) {
  DetectionList found;
  found.push_back(at(0, 0, 0, 100, 14));     // exit-left on the sign
  found.push_back(at(1, 5, 3, 100, 22));     // exit-right on the same sign: more inliers
  found.push_back(at(2, 300, 300, 50, 12));  // another sign elsewhere
  found.push_back(at(0, 2, 1, 98, 9));       // a repeat of the first
  keep_best_of_overlapping(found);
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].model_id, 1);
  EXPECT_EQ(found[1].model_id, 2);
}

TEST(Overlap, TiesGoToTheLargerMarginThenTheEarlier) {
  DetectionList found;
  found.push_back(at(0, 0, 0, 100, 20, 0.40, 0.10));
  found.push_back(at(1, 0, 0, 100, 20, 0.60, 0.10));
  keep_best_of_overlapping(found);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].model_id, 1);
  DetectionList same;
  same.push_back(at(4, 0, 0, 100, 20));
  same.push_back(at(5, 0, 0, 100, 20));
  keep_best_of_overlapping(same);
  ASSERT_EQ(same.size(), 1u);
  EXPECT_EQ(same[0].model_id, 4);
}

// With appearances, the model whose image matches the frame clearly better
// wins over one with more keypoint support; alike correlations leave it to
// the inliers.
TEST(Overlap, TheClearlyBetterAppearanceWins) {
  DetectionList found;
  Detection left = at(0, 0, 0, 100, 30), right = at(1, 4, 2, 100, 14);
  left.appearance = 0.72;
  right.appearance = 0.93;
  found.push_back(left);
  found.push_back(right);
  keep_best_of_overlapping(found);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].model_id, 1);

  DetectionList alike;
  right.appearance = 0.75;
  alike.push_back(left);
  alike.push_back(right);
  keep_best_of_overlapping(alike);
  ASSERT_EQ(alike.size(), 1u);
  EXPECT_EQ(alike[0].model_id, 0);  // more inliers

  DetectionList one_measured;
  right.appearance = 0.93;
  left.appearance = -1.0;  // not measured
  one_measured.push_back(left);
  one_measured.push_back(right);
  keep_best_of_overlapping(one_measured);
  ASSERT_EQ(one_measured.size(), 1u);
  EXPECT_EQ(one_measured[0].model_id, 0);
}

// Three detections of one sign whose pairwise preferences would form a
// cycle (A's image clearly better than B's, C more inliers than A with an
// image only slightly better than B's): one of them is kept, never none.
TEST(Overlap, AGroupAlwaysKeepsOne) {
  Detection a = at(0, 0, 0, 100, 10), b = at(1, 2, 1, 100, 30), c = at(2, 1, 2, 100, 20);
  a.appearance = 0.90;
  b.appearance = 0.84;
  c.appearance = 0.87;
  for (int rotation = 0; rotation < 3; ++rotation) {
    DetectionList found;
    const Detection order[3] = {a, b, c};
    for (int i = 0; i < 3; ++i) found.push_back(order[(i + rotation) % 3]);
    keep_best_of_overlapping(found);
    ASSERT_EQ(found.size(), 1u) << "rotation " << rotation;
    EXPECT_EQ(found[0].model_id, 0);  // the best image that beat the best-supported one
  }
}

}  // namespace
}  // namespace kg
