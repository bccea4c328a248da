// Detection::confidence (core/pose/confidence.h): a probability that rises with
// the support a pose has and falls with its reprojection error.
#include <gtest/gtest.h>

#include "core/pose/confidence.h"

namespace kg {
namespace {

Detection with_support(int inliers, double score, double chance, double rms) {
  Detection d;
  d.inliers = inliers;
  d.inlier_keygraphs = inliers / 3;
  d.score = score;
  d.chance = chance;
  d.verification_z = 10.0 * (score - chance);
  d.rms_error = rms;
  return d;
}

TEST(Confidence, IsAProbabilityForAnySupport) {
  for (int inliers : {0, 1, 12, 100, 100000}) {
    for (double score : {0.0, 0.2, 1.0}) {
      for (double rms : {0.0, 1.0, 4.0, 1e6}) {
        const double c = detection_confidence(with_support(inliers, score, 0.05, rms));
        EXPECT_GE(c, 0.0);
        EXPECT_LE(c, 1.0);
      }
    }
  }
}

TEST(Confidence, RisesWithInliersAndSupportAboveChance) {
  const double base = detection_confidence(with_support(12, 0.15, 0.05, 1.5));
  EXPECT_GT(detection_confidence(with_support(40, 0.15, 0.05, 1.5)), base);
  EXPECT_GT(detection_confidence(with_support(12, 0.45, 0.05, 1.5)), base);
  EXPECT_LT(detection_confidence(with_support(12, 0.15, 0.05, 3.5)), base);
  // A minimal detection (12 inliers, support barely above chance) is a coin
  // toss or worse; a well-supported one (50 inliers, half the keypoints
  // re-found) is near certain: the two ends of what the benchmark saw.
  EXPECT_LT(detection_confidence(with_support(12, 0.08, 0.05, 2.5)), 0.5);
  EXPECT_GT(detection_confidence(with_support(50, 0.5, 0.05, 1.0)), 0.95);
}

// With an appearance correlation (format 6.2 indexes) the other model is
// used; it too must rise with every kind of support.
TEST(Confidence, WithAnAppearanceRisesWithSupportAndCorrelation) {
  const auto with = [](int inliers, double score, double rms, double appearance) {
    Detection d = with_support(inliers, score, 0.05, rms);
    d.appearance = appearance;
    return detection_confidence(d);
  };
  const double base = with(12, 0.15, 1.5, 0.8);
  EXPECT_NE(base, detection_confidence(with_support(12, 0.15, 0.05, 1.5)));  // the other model
  EXPECT_GT(with(40, 0.15, 1.5, 0.8), base);
  EXPECT_GT(with(12, 0.45, 1.5, 0.8), base);
  EXPECT_GT(with(12, 0.15, 1.5, 0.95), base);
  EXPECT_LT(with(12, 0.15, 3.5, 0.8), base);
  Detection more_z = with_support(12, 0.15, 0.05, 1.5);
  more_z.appearance = 0.8;
  more_z.verification_z = 30.0;
  EXPECT_GE(detection_confidence(more_z), base);
  // A pose whose image does not match is unlikely whatever its keypoints;
  // a well-supported one that matches is near certain.
  EXPECT_LT(with(50, 0.5, 1.0, 0.3), 0.5);
  EXPECT_GT(with(50, 0.5, 1.0, 0.95), 0.95);
}

}  // namespace
}  // namespace kg
