// Homography fitting, refinement and pose plausibility on synthetic
// correspondences with a known ground-truth homography.
#include "core/pose/homography.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include "core/support/rng.h"

namespace kg {
namespace {

constexpr float kModelW = 640.f;
constexpr float kModelH = 480.f;

// Close to the Oxford graf 1->3 ground truth: rotation, shear and a
// moderate perspective (w goes from 0.99 to 1.22 across the model).
const Homography kPerspective = {0.7629, -0.2992,  225.67,    0.3344, 1.0144,
                                 -77.0,  3.466e-4, -1.436e-5, 1.0};

double dist(Point2f a, Point2f b) {
  return std::hypot(a.x - b.x, a.y - b.y);
}

double gaussian(Rng& rng) {
  const double u1 = 1.0 - rng.uniform01();  // (0, 1]: log is finite
  const double u2 = rng.uniform01();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

std::vector<Point2f> random_model_points(Rng& rng, int n) {
  std::vector<Point2f> pts(n);
  for (auto& p : pts) {
    p.x = static_cast<float>(rng.uniform01() * kModelW);
    p.y = static_cast<float>(rng.uniform01() * kModelH);
  }
  return pts;
}

std::vector<Point2f> map_points(const Homography& h, const std::vector<Point2f>& model) {
  std::vector<Point2f> out;
  for (const Point2f& p : model) out.push_back(kg::apply(h, p));
  return out;
}

// Largest distance between the images of the model corners under a and b,
// relative to the distance of the true corner from the origin.
double corner_relative_error(const Homography& fit, const Homography& truth) {
  const Point2f corners[4] = {{0.f, 0.f}, {kModelW, 0.f}, {kModelW, kModelH}, {0.f, kModelH}};
  double worst = 0.0;
  for (const Point2f& c : corners) {
    const Point2f t = kg::apply(truth, c);
    worst = std::max(worst, dist(kg::apply(fit, c), t) / std::hypot(t.x, t.y));
  }
  return worst;
}

double corner_pixel_error(const Homography& fit, const Homography& truth) {
  const Point2f corners[4] = {{0.f, 0.f}, {kModelW, 0.f}, {kModelW, kModelH}, {0.f, kModelH}};
  double worst = 0.0;
  for (const Point2f& c : corners)
    worst = std::max(worst, dist(kg::apply(fit, c), kg::apply(truth, c)));
  return worst;
}

Homography similarity(double angle, double scale, double tx, double ty) {
  const double c = scale * std::cos(angle);
  const double s = scale * std::sin(angle);
  return {c, -s, tx, s, c, ty, 0.0, 0.0, 1.0};
}

TEST(FitHomography, RecoversPerspectiveFromFourPoints) {
  const std::vector<Point2f> model = {{20.f, 30.f}, {610.f, 15.f}, {625.f, 460.f}, {10.f, 440.f}};
  const std::vector<Point2f> scene = map_points(kPerspective, model);
  Homography h{};
  ASSERT_TRUE(fit_homography(model.data(), scene.data(), 4, h));
  EXPECT_DOUBLE_EQ(h[8], 1.0);
  EXPECT_LT(corner_relative_error(h, kPerspective), 1e-6);
  EXPECT_LT(rms_reprojection_error(model.data(), scene.data(), 4, h), 1e-3);
}

TEST(FitHomography, RecoversPerspectiveFromFiftyPoints) {
  Rng rng(7);
  const std::vector<Point2f> model = random_model_points(rng, 50);
  const std::vector<Point2f> scene = map_points(kPerspective, model);
  Homography h{};
  ASSERT_TRUE(fit_homography(model.data(), scene.data(), 50, h));
  EXPECT_DOUBLE_EQ(h[8], 1.0);
  EXPECT_LT(corner_relative_error(h, kPerspective), 1e-6);
  for (int i = 0; i < 9; ++i)
    EXPECT_NEAR(h[i], kPerspective[i], 1e-6 * (1.0 + std::abs(kPerspective[i])));
}

TEST(FitHomography, RecoversHomographyWhoseNormalisedH33IsZero) {
  // The model centroid (320, 240) maps to infinity: the 8x8 system with
  // h33 = 1 in normalised coordinates is singular, the null-space fallback
  // must still find H (here h33 = 1 in pixels: w = 1 - x / 320).
  const Homography truth = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0 / 320.0, 0.0, 1.0};
  const std::vector<Point2f> model = {{0.f, 0.f}, {640.f, 0.f}, {640.f, 480.f}, {0.f, 480.f}};
  const std::vector<Point2f> scene = map_points(truth, model);
  Homography h{};
  ASSERT_TRUE(fit_homography(model.data(), scene.data(), 4, h));
  const Point2f probes[3] = {{100.f, 50.f}, {200.f, 400.f}, {500.f, 300.f}};
  for (const Point2f& p : probes) EXPECT_LT(dist(kg::apply(h, p), kg::apply(truth, p)), 1e-3);
}

TEST(FitHomography, RejectsDegenerateInput) {
  Homography h{};
  const std::vector<Point2f> good = {{20.f, 30.f}, {610.f, 15.f}, {625.f, 460.f}, {10.f, 440.f}};
  const std::vector<Point2f> good_scene = map_points(kPerspective, good);
  ASSERT_TRUE(fit_homography(good.data(), good_scene.data(), 4, h));

  // Three model points on a line.
  const std::vector<Point2f> collinear = {
      {0.f, 0.f}, {300.f, 150.f}, {600.f, 300.f}, {50.f, 400.f}};
  EXPECT_FALSE(fit_homography(collinear.data(), good_scene.data(), 4, h));
  // ... and the same in the scene.
  EXPECT_FALSE(fit_homography(good.data(), collinear.data(), 4, h));
  // Nearly collinear: 0.2 px off a 600 px line is within the tolerance.
  const std::vector<Point2f> nearly = {{0.f, 0.f}, {300.f, 150.2f}, {600.f, 300.f}, {50.f, 400.f}};
  EXPECT_FALSE(fit_homography(nearly.data(), good_scene.data(), 4, h));
  // Two coincident points.
  const std::vector<Point2f> coincident = {
      {20.f, 30.f}, {20.f, 30.f}, {625.f, 460.f}, {10.f, 440.f}};
  EXPECT_FALSE(fit_homography(coincident.data(), good_scene.data(), 4, h));
  // All points the same.
  const std::vector<Point2f> same(6, Point2f{5.f, 5.f});
  const std::vector<Point2f> same_scene = map_points(kPerspective, same);
  EXPECT_FALSE(fit_homography(same.data(), same_scene.data(), 6, h));
  // Too few points.
  EXPECT_FALSE(fit_homography(good.data(), good_scene.data(), 3, h));
  // Many points, all on one line (least-squares path).
  std::vector<Point2f> line;
  for (int i = 0; i < 12; ++i)
    line.push_back({10.f + 45.f * static_cast<float>(i), 20.f + 30.f * static_cast<float>(i)});
  const std::vector<Point2f> line_scene = map_points(kPerspective, line);
  EXPECT_FALSE(fit_homography(line.data(), line_scene.data(), 12, h));
  // Many points: four on one line and one off it leave H underdetermined.
  std::vector<Point2f> four_plus_one(line.begin(), line.begin() + 4);
  four_plus_one.push_back({300.f, 10.f});
  const std::vector<Point2f> fpo_scene = map_points(kPerspective, four_plus_one);
  EXPECT_FALSE(fit_homography(four_plus_one.data(), fpo_scene.data(), 5, h));
  // Non-finite input.
  std::vector<Point2f> bad = good;
  bad[2].x = std::nanf("");
  EXPECT_FALSE(fit_homography(bad.data(), good_scene.data(), 4, h));
}

TEST(FitHomography, AcceptsSlightlyNonCollinearMinimalSet) {
  // 20 px off a 600 px line is well above the tolerance.
  const std::vector<Point2f> model = {{0.f, 0.f}, {300.f, 170.f}, {600.f, 300.f}, {50.f, 400.f}};
  const std::vector<Point2f> scene = map_points(kPerspective, model);
  Homography h{};
  ASSERT_TRUE(fit_homography(model.data(), scene.data(), 4, h));
  EXPECT_LT(corner_relative_error(h, kPerspective), 1e-5);
}

TEST(RmsReprojectionError, MatchesHandComputedValue) {
  const Homography id = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const std::vector<Point2f> model = {{0.f, 0.f}, {10.f, 0.f}};
  const std::vector<Point2f> scene = {{3.f, 4.f}, {10.f, 0.f}};
  // Squared errors 25 and 0: RMS sqrt(25 / 2).
  EXPECT_NEAR(rms_reprojection_error(model.data(), scene.data(), 2, id), std::sqrt(12.5), 1e-12);
}

struct NoisyData {
  std::vector<Point2f> model;
  std::vector<Point2f> scene;
};

NoisyData noisy_correspondences(int n, double sigma, std::uint64_t seed) {
  Rng rng(seed);
  NoisyData d;
  d.model = random_model_points(rng, n);
  for (const Point2f& m : d.model) {
    const Point2f s = kg::apply(kPerspective, m);
    d.scene.push_back({static_cast<float>(s.x + sigma * gaussian(rng)),
                       static_cast<float>(s.y + sigma * gaussian(rng))});
  }
  return d;
}

// The RANSAC hypothesis fit (least squares with h33 = 1 for n > 4) against
// the null-space fit: the same homography from exact correspondences, as
// close to the truth from noisy ones, and the same degenerate sets refused.
TEST(FitHomographyHypothesis, AgreesWithTheNullSpaceFit) {
  for (int n = 4; n <= 8; ++n) {
    Rng rng(static_cast<std::uint64_t>(100 + n));
    const std::vector<Point2f> model = random_model_points(rng, n);
    const std::vector<Point2f> scene = map_points(kPerspective, model);
    Homography fast{}, reference{};
    ASSERT_TRUE(fit_homography_hypothesis(model.data(), scene.data(), n, fast)) << n;
    ASSERT_TRUE(fit_homography(model.data(), scene.data(), n, reference)) << n;
    EXPECT_LT(corner_relative_error(fast, kPerspective), 1e-5) << n;  // float points
    EXPECT_LT(corner_pixel_error(fast, reference), 1e-4) << n;
  }
  // Noisy samples of 6 and 8 points (two or four circuits' worth): over
  // many draws the corners are as far from the truth as the null-space
  // fit's, within 10 %.
  for (int n : {6, 8}) {
    double fast_error = 0.0, reference_error = 0.0;
    int fitted = 0;
    for (int trial = 0; trial < 300; ++trial) {
      const NoisyData d =
          noisy_correspondences(n, 1.0, static_cast<std::uint64_t>(1000 * n + trial));
      Homography fast{}, reference{};
      if (!fit_homography(d.model.data(), d.scene.data(), n, reference)) continue;
      ASSERT_TRUE(fit_homography_hypothesis(d.model.data(), d.scene.data(), n, fast)) << trial;
      fast_error += corner_pixel_error(fast, kPerspective);
      reference_error += corner_pixel_error(reference, kPerspective);
      ++fitted;
    }
    ASSERT_GT(fitted, 290) << n;
    std::printf("n = %d: mean corner error %.3f px (h33 = 1 least squares), %.3f px (null space)\n",
                n, fast_error / fitted, reference_error / fitted);
    EXPECT_LT(fast_error, 1.1 * reference_error) << n;
  }
  // Degenerate: four points on a line and one off it; all on a line.
  std::vector<Point2f> line;
  for (int i = 0; i < 8; ++i)
    line.push_back({10.f + 45.f * static_cast<float>(i), 20.f + 30.f * static_cast<float>(i)});
  const std::vector<Point2f> line_scene = map_points(kPerspective, line);
  Homography h{};
  EXPECT_FALSE(fit_homography_hypothesis(line.data(), line_scene.data(), 8, h));
  std::vector<Point2f> four_plus_one(line.begin(), line.begin() + 4);
  four_plus_one.push_back({300.f, 10.f});
  const std::vector<Point2f> fpo_scene = map_points(kPerspective, four_plus_one);
  EXPECT_FALSE(fit_homography_hypothesis(four_plus_one.data(), fpo_scene.data(), 5, h));
}

TEST(RefineHomography, LowersErrorToNoiseLevelFromPerturbedStart) {
  const double sigma = 0.5;
  const int n = 50;
  const NoisyData d = noisy_correspondences(n, sigma, 11);
  Homography h = kPerspective;
  h[0] *= 1.02;
  h[2] += 6.0;
  h[5] -= 4.0;
  h[6] += 4e-5;
  const double start = rms_reprojection_error(d.model.data(), d.scene.data(), n, h);
  const double at_truth = rms_reprojection_error(d.model.data(), d.scene.data(), n, kPerspective);
  ASSERT_GT(start, 5.0);

  const double refined = refine_homography(d.model.data(), d.scene.data(), n, h);
  EXPECT_LT(refined, start);
  EXPECT_DOUBLE_EQ(refined, rms_reprojection_error(d.model.data(), d.scene.data(), n, h));
  EXPECT_DOUBLE_EQ(h[8], 1.0);
  // The least-squares optimum is at most the error of the true H, and with
  // 100 residuals and 8 parameters only slightly below it.
  EXPECT_LE(refined, at_truth * (1.0 + 1e-6));
  EXPECT_GT(refined, 0.85 * at_truth);
  // Per point, E|r|^2 = 2 sigma^2 at the truth.
  EXPECT_NEAR(refined, sigma * std::sqrt(2.0), 0.15);
  EXPECT_LT(corner_pixel_error(h, kPerspective), 1.0);
}

TEST(RefineHomography, ImprovesOnTheAlgebraicFit) {
  const int n = 40;
  const NoisyData d = noisy_correspondences(n, 1.0, 12);
  Homography h{};
  ASSERT_TRUE(fit_homography(d.model.data(), d.scene.data(), n, h));
  const double dlt = rms_reprojection_error(d.model.data(), d.scene.data(), n, h);
  const double refined = refine_homography(d.model.data(), d.scene.data(), n, h);
  // DLT minimises an algebraic error, so the geometric optimum is lower.
  EXPECT_LT(refined, dlt);
}

TEST(RefineHomography, NeverReturnsAWorseHomography) {
  const int n = 30;
  const NoisyData d = noisy_correspondences(n, 0.5, 13);
  Homography h = kPerspective;
  const double first = refine_homography(d.model.data(), d.scene.data(), n, h);
  // From the optimum: no change for the worse.
  const Homography optimum = h;
  const double second = refine_homography(d.model.data(), d.scene.data(), n, h);
  EXPECT_LE(second, first);
  EXPECT_LT(corner_pixel_error(h, optimum), 1e-3);
  // Zero iterations: the input comes back unchanged with its own error.
  Homography start = kPerspective;
  start[2] += 3.0;
  const Homography before = start;
  const double err = refine_homography(d.model.data(), d.scene.data(), n, start, 0);
  EXPECT_EQ(start, before);
  EXPECT_DOUBLE_EQ(err, rms_reprojection_error(d.model.data(), d.scene.data(), n, before));
  // A far-off start (mirrored) may not reach the optimum but never gets worse.
  Homography mirrored = {-1, 0, 640, 0, 1, 0, 0, 0, 1};
  const double mirrored_before =
      rms_reprojection_error(d.model.data(), d.scene.data(), n, mirrored);
  const double mirrored_after = refine_homography(d.model.data(), d.scene.data(), n, mirrored);
  EXPECT_LE(mirrored_after, mirrored_before);
  EXPECT_DOUBLE_EQ(mirrored_after,
                   rms_reprojection_error(d.model.data(), d.scene.data(), n, mirrored));
}

bool plausible(const Homography& h, float w = kModelW, float hgt = kModelH) {
  return is_plausible_pose(h, w, hgt, RansacParams{});
}

// Rotation about the model centre composed with a scale and a shift.
Homography rotation_about_centre(double angle, double scale) {
  const Homography r = similarity(angle, scale, 0.0, 0.0);
  const double cx = kModelW / 2.0;
  const double cy = kModelH / 2.0;
  Homography h = r;
  h[2] = cx + 100.0 - (r[0] * cx + r[1] * cy);
  h[5] = cy + 50.0 - (r[3] * cx + r[4] * cy);
  return h;
}

TEST(IsPlausiblePose, AcceptsIdentityRotationAndModeratePerspective) {
  EXPECT_TRUE(plausible({1, 0, 0, 0, 1, 0, 0, 0, 1}));
  EXPECT_TRUE(plausible(rotation_about_centre(0.5, 1.0)));
  EXPECT_TRUE(plausible(rotation_about_centre(-2.5, 0.6)));  // upside down is not a mirror
  EXPECT_TRUE(plausible(kPerspective));
  // Overall scale does not matter.
  Homography scaled = kPerspective;
  for (double& v : scaled) v *= -3.0;
  EXPECT_TRUE(plausible(scaled));
  // Area ratio 2.5^2 = 6.25 is inside [1/8, 8].
  EXPECT_TRUE(plausible(similarity(0.0, 2.5, 0.0, 0.0)));
  EXPECT_TRUE(plausible(similarity(0.0, 0.4, 0.0, 0.0)));  // 0.16 >= 1/8
}

TEST(IsPlausiblePose, RejectsMirror) {
  EXPECT_FALSE(plausible({-1, 0, 640, 0, 1, 0, 0, 0, 1}));
  EXPECT_FALSE(plausible({1, 0, 0, 0, -1, 480, 0, 0, 1}));
  // A mirrored perspective pose.
  Homography mirrored = kPerspective;
  mirrored[0] = -mirrored[0];
  mirrored[3] = -mirrored[3];
  mirrored[6] = -mirrored[6];
  EXPECT_FALSE(plausible(mirrored));
}

TEST(IsPlausiblePose, RejectsCollapse) {
  // Rank-deficient: everything maps onto the line y = x.
  EXPECT_FALSE(plausible({1, 0, 0, 1, 0, 0, 0, 0, 1}));
  // Everything maps to one point.
  EXPECT_FALSE(plausible({0, 0, 10, 0, 0, 10, 0, 0, 1}));
  // A side shorter than 4 px while the area ratio (2 * 0.18 = 0.36) is fine.
  EXPECT_FALSE(plausible({2.0, 0, 0, 0, 0.18, 0, 0, 0, 1}, 20.f, 20.f));
  EXPECT_TRUE(plausible({2.0, 0, 0, 0, 0.25, 0, 0, 0, 1}, 20.f, 20.f));
  // Not finite.
  EXPECT_FALSE(plausible({std::nan(""), 0, 0, 0, 1, 0, 0, 0, 1}));
  EXPECT_FALSE(plausible({1, 0, 0, 0, 1, 0, 0, 0, 0}));  // origin at infinity
}

TEST(IsPlausiblePose, RejectsExtremeScale) {
  EXPECT_FALSE(plausible(similarity(0.3, 3.0, 0.0, 0.0)));   // area x9
  EXPECT_FALSE(plausible(similarity(0.3, 0.25, 0.0, 0.0)));  // area x1/16
  RansacParams loose;
  loose.max_scale_change = 10.0;
  EXPECT_TRUE(is_plausible_pose(similarity(0.3, 3.0, 0.0, 0.0), kModelW, kModelH, loose));
}

TEST(IsPlausiblePose, RejectsExtremePerspective) {
  // |h31| * 640 = 6.4 > 0.005 * 640: w runs from 1 to 7.4 across the model.
  EXPECT_FALSE(plausible({1, 0, 0, 0, 1, 0, 0.01, 0, 1}));
  EXPECT_FALSE(plausible({1, 0, 0, 0, 1, 0, 0, 0.01, 1}));
  // Only the perspective bound fails: |h31| * 640 = 3.84 > 3.2, while w > 0,
  // the quadrilateral is convex and its area ratio (about 0.78) is fine.
  EXPECT_FALSE(plausible({2.5, 0, 0, 0, 2.5, 0, 0.006, 0, 1}));
  EXPECT_TRUE(plausible({2.5, 0, 0, 0, 2.5, 0, 0.004, 0, 1}));
  RansacParams loose;
  loose.max_perspective = 0.01;
  EXPECT_TRUE(is_plausible_pose({2.5, 0, 0, 0, 2.5, 0, 0.006, 0, 1}, kModelW, kModelH, loose));
  // Within the bound but the far corners are behind the camera (w < 0;
  // their images also reverse the quadrilateral's orientation).
  EXPECT_FALSE(plausible({1, 0, 0, 0, 1, 0, -0.003, 0, 1}));
  // Within the bound, w > 0 and convex: accepted.
  EXPECT_TRUE(plausible({1, 0, 0, 0, 1, 0, 0.001, 0, 1}));
  // Fold-over: the line at infinity crosses the model rectangle.
  EXPECT_FALSE(plausible({1, 0, 0, 0, 1, 0, -0.002, -0.002, 1}));
}

}  // namespace
}  // namespace kg
