// Photometric pose refinement (core/pose/appearance_align.h) on a real image:
// box.png rendered into a real background under a known homography; the
// aligner must bring a pose several pixels off back to the truth, under a
// lighting change too, tell the right appearance from another one, and
// allocate nothing once reserved.
#include "core/pose/appearance_align.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "core/support/simd_dispatch.h"
#include "support/alloc_counter.h"
#include "support/simd_scope.h"
#include "support/test_data.h"

namespace kg {
namespace {

constexpr int kAppearanceSize = 128;

struct Scene {
  cv::Mat model;       // the model image (model pixels)
  cv::Mat appearance;  // model resampled by area to a 128 px long edge
  float scale_x = 0.f, scale_y = 0.f;
  cv::Mat frame;       // blurred frame holding the model
  Homography truth{};  // model pixels -> frame pixels
};

Homography from_corners(const cv::Mat& model, const std::vector<cv::Point2f>& frame_corners) {
  const float w = static_cast<float>(model.cols - 1), h = static_cast<float>(model.rows - 1);
  const std::vector<cv::Point2f> src = {{0.f, 0.f}, {w, 0.f}, {w, h}, {0.f, h}};
  const cv::Mat m = cv::getPerspectiveTransform(src, frame_corners);
  Homography out{};
  for (int i = 0; i < 9; ++i)
    out[static_cast<std::size_t>(i)] = m.at<double>(i / 3, i % 3) / m.at<double>(2, 2);
  return out;
}

cv::Mat to_mat(const Homography& h) {
  cv::Mat m(3, 3, CV_64F);
  for (int i = 0; i < 9; ++i) m.at<double>(i / 3, i % 3) = h[static_cast<std::size_t>(i)];
  return m;
}

Scene make_scene(const std::vector<cv::Point2f>& corners) {
  Scene s;
  s.model = test::load_gray(test::opencv_data("box.png"));
  cv::Mat background = test::load_gray(test::opencv_data("building.jpg"));
  if (s.model.empty() || background.empty()) return s;
  // As the index stores it: resampled by area to a given size, so each
  // axis has its own scale.
  const double factor = static_cast<double>(kAppearanceSize) / std::max(s.model.cols, s.model.rows);
  const cv::Size size(static_cast<int>(std::lround(s.model.cols * factor)),
                      static_cast<int>(std::lround(s.model.rows * factor)));
  cv::resize(s.model, s.appearance, size, 0, 0, cv::INTER_AREA);
  s.scale_x = static_cast<float>(s.appearance.cols) / static_cast<float>(s.model.cols);
  s.scale_y = static_cast<float>(s.appearance.rows) / static_cast<float>(s.model.rows);
  cv::resize(background, background, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
  s.truth = from_corners(s.model, corners);
  cv::Mat frame = background.clone();
  cv::warpPerspective(s.model, frame, to_mat(s.truth), frame.size(), cv::INTER_LINEAR,
                      cv::BORDER_TRANSPARENT);
  cv::GaussianBlur(frame, s.frame, cv::Size(0, 0), 1.0);
  return s;
}

AppearanceImage image_of(const Scene& s) {
  return {s.appearance.data, s.appearance.cols, s.appearance.rows, s.scale_x, s.scale_y};
}

double max_corner_error(const Scene& s, const Homography& h) {
  const float w = static_cast<float>(s.model.cols - 1), hh = static_cast<float>(s.model.rows - 1);
  const Point2f corners[4] = {{0.f, 0.f}, {w, 0.f}, {w, hh}, {0.f, hh}};
  double worst = 0.0;
  for (const Point2f& c : corners) {
    const Point2f a = kg::apply(h, c), b = kg::apply(s.truth, c);
    worst = std::max(worst, std::hypot(double{a.x - b.x}, double{a.y - b.y}));
  }
  return worst;
}

// The truth with each frame corner moved by `offsets`.
Homography perturbed(const Scene& s, const std::vector<cv::Point2f>& corners,
                     const std::vector<cv::Point2f>& offsets) {
  std::vector<cv::Point2f> moved = corners;
  for (std::size_t i = 0; i < moved.size(); ++i) moved[i] += offsets[i];
  return from_corners(s.model, moved);
}

const std::vector<cv::Point2f> kCorners = {
    {180.f, 120.f}, {430.f, 150.f}, {420.f, 330.f}, {170.f, 310.f}};
const std::vector<cv::Point2f> kOffsets = {{6.f, -5.f}, {-7.f, 4.f}, {5.f, 7.f}, {-4.f, -6.f}};

TEST(AppearanceAlign, BringsAPoseSeveralPixelsOffToSubPixel) {
  const Scene s = make_scene(kCorners);
  ASSERT_FALSE(s.frame.empty()) << "box.png or building.jpg missing";
  Homography h = perturbed(s, kCorners, kOffsets);
  ASSERT_GT(max_corner_error(s, h), 6.0);
  AppearanceAligner aligner;
  aligner.reserve(kAppearanceSize * kAppearanceSize);
  const AppearanceFit fit = aligner.align(image_of(s), test::view(s.frame), h);
  EXPECT_TRUE(fit.measured);
  EXPECT_TRUE(fit.aligned);
  EXPECT_LT(max_corner_error(s, h), 0.5);
  EXPECT_GT(fit.ncc, 0.95);
  EXPECT_GT(fit.ncc, fit.ncc_before);
}

TEST(AppearanceAlign, SameFitWithWorkers) {
  // The frame sampled, the steepest-descent images projected and the
  // normal equations summed on 1 to 4 threads: the same fit, bit for bit.
  const Scene s = make_scene(kCorners);
  ASSERT_FALSE(s.frame.empty());
  AppearanceAligner alone;
  alone.reserve(kAppearanceSize * kAppearanceSize);
  Homography reference = perturbed(s, kCorners, kOffsets);
  const AppearanceFit first = alone.align(image_of(s), test::view(s.frame), reference);
  ASSERT_TRUE(first.aligned);
  for (int threads : {2, 3, 4}) {
    WorkerPool pool(threads);
    AppearanceAligner aligner;
    aligner.reserve(kAppearanceSize * kAppearanceSize);
    aligner.set_workers(&pool);
    for (int round = 0; round < 2; ++round) {
      Homography h = perturbed(s, kCorners, kOffsets);
      const AppearanceFit fit = aligner.align(image_of(s), test::view(s.frame), h);
      EXPECT_EQ(h, reference) << threads << " threads";
      EXPECT_EQ(fit.ncc, first.ncc) << threads << " threads";
      EXPECT_EQ(fit.ncc_before, first.ncc_before) << threads << " threads";
      EXPECT_EQ(fit.iterations, first.iterations) << threads << " threads";
    }
  }
}

#if defined(__x86_64__) || defined(__aarch64__)
// The vector loops (AVX2 on x86-64, NEON on AArch64: the frame sampling, 4
// pixels at a time; the normal equations, 4 or 2 entries at a time) against
// the portable loops: the same fit, bit for bit, for a pose several pixels
// off (several samples a level pixel), a small instance (one sample), and
// a pose with a fifth of the model outside the frame (pixels whose samples
// leave it part of the way through, beside pixels whose samples all stay
// inside). (The ARM cross-builds, without OpenCV, run the same comparison
// on the golden frames: test_vector_kernels.cpp.)
TEST(AppearanceAlign, SameFitAtEverySimdLevel) {
#if defined(__x86_64__)
  if (best_simd_level() != SimdLevel::kAvx2) GTEST_SKIP() << "needs a CPU with AVX2";
#endif
  const std::vector<std::vector<cv::Point2f>> poses = {
      kCorners,
      {{300.f, 200.f}, {360.f, 206.f}, {358.f, 247.f}, {298.f, 242.f}},
      {{-50.f, 120.f}, {200.f, 150.f}, {190.f, 330.f}, {-60.f, 310.f}}};
  int measured = 0;
  for (const std::vector<cv::Point2f>& corners : poses) {
    const Scene s = make_scene(corners);
    ASSERT_FALSE(s.frame.empty());
    AppearanceAligner aligner;
    aligner.reserve(kAppearanceSize * kAppearanceSize);
    Homography vector_h = perturbed(s, corners, kOffsets);
    Homography portable_h = vector_h;
    AppearanceFit vector_fit, portable_fit;
    {
      const test::SimdScope best(best_simd_level());
      vector_fit = aligner.align(image_of(s), test::view(s.frame), vector_h);
    }
    {
      const test::SimdScope scalar(SimdLevel::kScalar);
      portable_fit = aligner.align(image_of(s), test::view(s.frame), portable_h);
    }
    EXPECT_EQ(vector_fit.measured, portable_fit.measured);
    EXPECT_EQ(vector_fit.aligned, portable_fit.aligned);
    EXPECT_EQ(vector_h, portable_h);
    EXPECT_EQ(vector_fit.ncc, portable_fit.ncc);
    EXPECT_EQ(vector_fit.ncc_before, portable_fit.ncc_before);
    EXPECT_EQ(vector_fit.iterations, portable_fit.iterations);
    measured += vector_fit.measured ? 1 : 0;
  }
  EXPECT_EQ(measured, 3);
}
#endif

TEST(AppearanceAlign, IgnoresGainAndBias) {
  Scene s = make_scene(kCorners);
  ASSERT_FALSE(s.frame.empty());
  s.frame.convertTo(s.frame, CV_8U, 0.45, 70.0);  // darker, low contrast, lifted
  Homography h = perturbed(s, kCorners, kOffsets);
  AppearanceAligner aligner;
  aligner.reserve(kAppearanceSize * kAppearanceSize);
  const AppearanceFit fit = aligner.align(image_of(s), test::view(s.frame), h);
  EXPECT_TRUE(fit.aligned);
  EXPECT_LT(max_corner_error(s, h), 0.6);
  EXPECT_GT(fit.ncc, 0.9);
}

TEST(AppearanceAlign, AnotherImageAtTheSamePoseCorrelatesPoorly) {
  const Scene s = make_scene(kCorners);
  ASSERT_FALSE(s.frame.empty());
  // Another object's appearance of the same size: the right pose cannot
  // make it look like the frame.
  cv::Mat other = test::load_gray(test::opencv_data("graf1.png"));
  ASSERT_FALSE(other.empty());
  cv::resize(other, other, s.appearance.size(), 0, 0, cv::INTER_AREA);
  AppearanceAligner aligner;
  aligner.reserve(kAppearanceSize * kAppearanceSize);
  Homography right = s.truth, wrong = s.truth;
  const AppearanceFit fit_right = aligner.align(image_of(s), test::view(s.frame), right);
  const AppearanceFit fit_wrong = aligner.align(
      {other.data, other.cols, other.rows, s.scale_x, s.scale_y}, test::view(s.frame), wrong);
  ASSERT_TRUE(fit_right.measured);
  ASSERT_TRUE(fit_wrong.measured);
  EXPECT_GT(fit_right.ncc, 0.95);
  EXPECT_LT(fit_wrong.ncc, 0.4);
}

TEST(AppearanceAlign, AbandonsAfterTheCoarseLevelWhatCannotCorrelate) {
  // align()'s abandon_below: another object's appearance at the box's pose
  // (a false cluster) stops after the coarse level, its pose unchanged and
  // its correlation low, and with refuse_below before any step; the box
  // itself, several pixels off, is not abandoned and gets the same fit, bit
  // for bit, as without the tests.
  const Scene s = make_scene(kCorners);
  ASSERT_FALSE(s.frame.empty());
  cv::Mat other = test::load_gray(test::opencv_data("graf1.png"));
  ASSERT_FALSE(other.empty());
  cv::resize(other, other, s.appearance.size(), 0, 0, cv::INTER_AREA);
  const AppearanceImage wrong_image{other.data, other.cols, other.rows, s.scale_x, s.scale_y};
  AppearanceAligner aligner;
  aligner.reserve(kAppearanceSize * kAppearanceSize);
  constexpr double kAbandonBelow = 0.45;

  Homography full = perturbed(s, kCorners, kOffsets);
  const AppearanceFit wrong_full = aligner.align(wrong_image, test::view(s.frame), full);
  Homography stopped = perturbed(s, kCorners, kOffsets);
  const Homography before = stopped;
  const AppearanceFit wrong_stopped =
      aligner.align(wrong_image, test::view(s.frame), stopped, kAbandonBelow);
  std::printf(
      "another image: %d steps, correlation %.3f -> %.3f (coarse %.3f); abandoned after %d\n",
      wrong_full.iterations, wrong_full.ncc_before, wrong_full.ncc, wrong_full.ncc_coarse,
      wrong_stopped.iterations);
  ASSERT_TRUE(wrong_full.measured);
  EXPECT_FALSE(wrong_full.abandoned);
  EXPECT_TRUE(wrong_full.coarse_measured);
  EXPECT_LT(wrong_full.ncc, 0.4);  // rejected either way
  EXPECT_TRUE(wrong_stopped.measured);
  EXPECT_TRUE(wrong_stopped.abandoned);
  EXPECT_FALSE(wrong_stopped.aligned);
  EXPECT_EQ(stopped, before);
  EXPECT_EQ(wrong_stopped.ncc, wrong_stopped.ncc_before);
  EXPECT_EQ(wrong_stopped.ncc_before, wrong_full.ncc_before);
  EXPECT_EQ(wrong_stopped.ncc_coarse, wrong_full.ncc_coarse);
  EXPECT_LT(wrong_stopped.ncc_coarse, kAbandonBelow);
  EXPECT_LT(wrong_stopped.iterations, wrong_full.iterations);  // the fine level's steps saved
  // refuse_below: not a step when the pose given correlates under it.
  Homography refused = before;
  const AppearanceFit wrong_refused =
      aligner.align(wrong_image, test::view(s.frame), refused, kAbandonBelow, 0.3);
  EXPECT_TRUE(wrong_refused.measured);
  EXPECT_TRUE(wrong_refused.abandoned);
  EXPECT_FALSE(wrong_refused.coarse_measured);
  EXPECT_EQ(wrong_refused.iterations, 0);
  EXPECT_EQ(refused, before);
  EXPECT_EQ(wrong_refused.ncc, wrong_full.ncc_before);

  Homography right_full = perturbed(s, kCorners, kOffsets);
  Homography right_tested = right_full;
  const AppearanceFit a = aligner.align(image_of(s), test::view(s.frame), right_full);
  const AppearanceFit b =
      aligner.align(image_of(s), test::view(s.frame), right_tested, kAbandonBelow, 0.3);
  EXPECT_FALSE(b.abandoned);
  EXPECT_TRUE(b.aligned);
  EXPECT_GT(b.ncc_coarse, kAbandonBelow);
  EXPECT_EQ(right_tested, right_full);
  EXPECT_EQ(b.ncc, a.ncc);
  EXPECT_EQ(b.iterations, a.iterations);
  EXPECT_LT(max_corner_error(s, right_tested), 0.5);
}

TEST(AppearanceAlign, LeavesAPoseMostlyOutsideTheFrameAlone) {
  const std::vector<cv::Point2f> corners = {
      {-300.f, 100.f}, {-50.f, 120.f}, {-60.f, 300.f}, {-310.f, 290.f}};
  const Scene s = make_scene(kCorners);
  ASSERT_FALSE(s.frame.empty());
  Homography h = from_corners(s.model, corners);
  const Homography before = h;
  AppearanceAligner aligner;
  aligner.reserve(kAppearanceSize * kAppearanceSize);
  const AppearanceFit fit = aligner.align(image_of(s), test::view(s.frame), h);
  EXPECT_FALSE(fit.measured);
  EXPECT_FALSE(fit.aligned);
  EXPECT_EQ(h, before);
}

TEST(AppearanceAlign, RefusesAnAppearanceLargerThanReserved) {
  const Scene s = make_scene(kCorners);
  ASSERT_FALSE(s.frame.empty());
  Homography h = perturbed(s, kCorners, kOffsets);
  const Homography before = h;
  AppearanceAligner aligner;
  aligner.reserve(64 * 64);
  const AppearanceFit fit = aligner.align(image_of(s), test::view(s.frame), h);
  EXPECT_FALSE(fit.measured);
  EXPECT_FALSE(fit.aligned);
  EXPECT_EQ(h, before);
}

// A model 60 px wide in the frame, half its appearance's size: scored at
// the half level, it still correlates like itself.
TEST(AppearanceAlign, ASmallInstanceIsScoredAtItsOwnResolution) {
  const std::vector<cv::Point2f> corners = {
      {300.f, 200.f}, {360.f, 206.f}, {358.f, 247.f}, {298.f, 242.f}};
  const Scene s = make_scene(corners);
  ASSERT_FALSE(s.frame.empty());
  Homography h = s.truth;
  AppearanceAligner aligner;
  aligner.reserve(kAppearanceSize * kAppearanceSize);
  const AppearanceFit fit = aligner.align(image_of(s), test::view(s.frame), h);
  ASSERT_TRUE(fit.measured);
  EXPECT_GT(fit.ncc, 0.85);
  EXPECT_LT(max_corner_error(s, h), 1.0);
}

TEST(AppearanceAlign, ADegeneratePoseIsNotMeasured) {
  const Scene s = make_scene(kCorners);
  ASSERT_FALSE(s.frame.empty());
  AppearanceAligner aligner;
  aligner.reserve(kAppearanceSize * kAppearanceSize);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const Homography& bad : {Homography{nan, 0, 0, 0, 1, 0, 0, 0, 1},
                                Homography{1, 0, inf, 0, 1, 0, 0, 0, 1}, Homography{}}) {
    Homography h = bad;
    const AppearanceFit fit = aligner.align(image_of(s), test::view(s.frame), h);
    EXPECT_FALSE(fit.measured);
    EXPECT_FALSE(fit.aligned);
  }
}

TEST(AppearanceAlign, AllocatesNothingOnceReserved) {
  const Scene s = make_scene(kCorners);
  ASSERT_FALSE(s.frame.empty());
  AppearanceAligner aligner;
  aligner.reserve(kAppearanceSize * kAppearanceSize);
  Homography h = perturbed(s, kCorners, kOffsets);
  test::AllocationCounter counter;
  const AppearanceFit fit = aligner.align(image_of(s), test::view(s.frame), h);
  EXPECT_EQ(counter.count(), 0);
  EXPECT_TRUE(fit.aligned);
}

}  // namespace
}  // namespace kg
