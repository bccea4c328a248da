// The triangle patch check (core/selection/triangle_patch.h) on a synthetic texture
// and its affine warp: a right triangle correspondence correlates high,
// also across a resolution change, a wrong one low, and triangles that
// cannot be judged (degenerate, tiny, flat, no appearance) are not measured.
#include "core/selection/triangle_patch.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "core/support/simd_dispatch.h"
#include "support/alloc_counter.h"

namespace kg {
namespace {

// Smoothed uniform noise: texture at every scale the tests use.
cv::Mat texture(int size, unsigned seed) {
  cv::Mat noise(size, size, CV_8U);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  cv::Mat smooth;
  cv::GaussianBlur(noise, smooth, cv::Size(), 2.0);
  cv::normalize(smooth, smooth, 0, 255, cv::NORM_MINMAX);
  return smooth;
}

ModelAppearance look_of(const cv::Mat& m, float scale) {
  ModelAppearance a;
  a.pixels = m.data;
  a.width = m.cols;
  a.height = m.rows;
  a.scale = scale;
  return a;
}

// Model pixels -> frame pixels: rotation by 25 degrees, scale 1.6, shear.
const cv::Matx23d kAffine(1.35, -0.80, 120.0, 0.62, 1.52, 40.0);

Point2f warp(const Point2f& p) {
  return {static_cast<float>(kAffine(0, 0) * p.x + kAffine(0, 1) * p.y + kAffine(0, 2)),
          static_cast<float>(kAffine(1, 0) * p.x + kAffine(1, 1) * p.y + kAffine(1, 2))};
}

class TrianglePatchTest : public ::testing::Test {
 protected:
  void SetUp() override {
    model_ = texture(200, 7);
    cv::warpAffine(model_, frame_, cv::Mat(kAffine), cv::Size(520, 520), cv::INTER_LINEAR);
    cv::GaussianBlur(frame_, frame_, cv::Size(), 0.8);
  }
  ImageView frame() const { return ImageView(frame_.data, frame_.cols, frame_.rows, frame_.step); }
  TrianglePatch check(const ModelAppearance& look, const Point2f* model,
                      const Point2f* scene) const {
    return triangle_patch_correlation(look, frame(), model, scene);
  }
  cv::Mat model_, frame_;
};

TEST_F(TrianglePatchTest, RightCorrespondenceCorrelatesHighWrongOneLow) {
  const ModelAppearance look = look_of(model_, 1.f);
  const Point2f model[3] = {{60.f, 60.f}, {110.f, 72.f}, {82.f, 120.f}};
  const Point2f scene[3] = {warp(model[0]), warp(model[1]), warp(model[2])};
  const TrianglePatch right = check(look, model, scene);
  ASSERT_TRUE(right.measured);
  EXPECT_GT(right.correlation, 0.9f);
  // The same model triangle paired with the frame triangle of another place.
  const Point2f elsewhere[3] = {{130.f, 140.f}, {180.f, 152.f}, {152.f, 190.f}};
  const Point2f wrong[3] = {warp(elsewhere[0]), warp(elsewhere[1]), warp(elsewhere[2])};
  const TrianglePatch other = check(look, model, wrong);
  ASSERT_TRUE(other.measured);
  EXPECT_LT(other.correlation, 0.5f);
  // Vertices paired in another order (the arcs' mirror image).
  const Point2f swapped[3] = {scene[1], scene[0], scene[2]};
  const TrianglePatch mirrored = check(look, model, swapped);
  ASSERT_TRUE(mirrored.measured);
  EXPECT_LT(mirrored.correlation, 0.5f);
}

TEST_F(TrianglePatchTest, ResolutionChangeStillCorrelates) {
  // The appearance stored at a third of the model's size (as the index
  // stores large models): the frame, five times finer, is averaged.
  cv::Mat small;
  cv::resize(model_, small, cv::Size(), 1.0 / 3.0, 1.0 / 3.0, cv::INTER_AREA);
  const ModelAppearance look =
      look_of(small, static_cast<float>(small.cols) / static_cast<float>(model_.cols));
  const Point2f model[3] = {{40.f, 50.f}, {130.f, 62.f}, {85.f, 140.f}};
  const Point2f scene[3] = {warp(model[0]), warp(model[1]), warp(model[2])};
  const TrianglePatch right = check(look, model, scene);
  ASSERT_TRUE(right.measured);
  EXPECT_GT(right.correlation, 0.85f);
  const Point2f swapped[3] = {scene[2], scene[1], scene[0]};
  const TrianglePatch wrong = check(look, model, swapped);
  ASSERT_TRUE(wrong.measured);
  EXPECT_LT(wrong.correlation, 0.5f);
}

TEST_F(TrianglePatchTest, UnjudgeableTrianglesAreNotMeasured) {
  const ModelAppearance look = look_of(model_, 1.f);
  // Collinear vertices.
  const Point2f line[3] = {{40.f, 40.f}, {80.f, 80.f}, {120.f, 120.f}};
  const Point2f line_scene[3] = {warp(line[0]), warp(line[1]), warp(line[2])};
  EXPECT_FALSE(check(look, line, line_scene).measured);
  // A triangle of a few pixels.
  const Point2f tiny[3] = {{50.f, 50.f}, {52.f, 50.f}, {50.f, 52.f}};
  const Point2f tiny_scene[3] = {warp(tiny[0]), warp(tiny[1]), warp(tiny[2])};
  EXPECT_FALSE(check(look, tiny, tiny_scene).measured);
  // Mostly outside the appearance.
  const Point2f outside[3] = {{190.f, 190.f}, {260.f, 200.f}, {220.f, 260.f}};
  const Point2f outside_scene[3] = {warp(outside[0]), warp(outside[1]), warp(outside[2])};
  EXPECT_FALSE(check(look, outside, outside_scene).measured);
  // No appearance stored, or a flat one.
  const Point2f model[3] = {{60.f, 60.f}, {110.f, 72.f}, {82.f, 120.f}};
  const Point2f scene[3] = {warp(model[0]), warp(model[1]), warp(model[2])};
  EXPECT_FALSE(check(ModelAppearance{}, model, scene).measured);
  const cv::Mat flat(200, 200, CV_8U, cv::Scalar(128));
  EXPECT_FALSE(check(look_of(flat, 1.f), model, scene).measured);
}

// The AVX2 lattice sampler (chosen at run time on x86-64) gives what the
// baseline one gives, bit for bit: random triangle pairs at every
// resolution ratio the check averages over (1 to 3 samples a side, in
// either image), many reaching past an image's border, in an appearance
// whose rows are narrower than the frame's stride. On a CPU or build
// without AVX2 both runs take the baseline path.
TEST_F(TrianglePatchTest, VectorSamplingEqualsBaseline) {
  cv::Mat small;
  cv::resize(model_, small, cv::Size(), 0.45, 0.45, cv::INTER_AREA);
  const ModelAppearance looks[2] = {
      look_of(model_, 1.f),
      look_of(small, static_cast<float>(small.cols) / static_cast<float>(model_.cols))};
  // The frame as a window of a wider buffer: stride > width.
  cv::Mat wide(frame_.rows, frame_.cols + 13, CV_8U, cv::Scalar(0));
  frame_.copyTo(wide(cv::Rect(0, 0, frame_.cols, frame_.rows)));
  const ImageView window(wide.data, frame_.cols, frame_.rows, wide.step);
  cv::RNG rng(11);
  const auto run = [&]() {
    std::vector<TrianglePatch> out;
    cv::RNG draw = rng;
    for (int t = 0; t < 3000; ++t) {
      Point2f model[3], scene[3];
      const float size = draw.uniform(6.f, 40.f);
      const float zoom = std::exp(draw.uniform(-1.4f, 1.4f));  // frame / model pixels
      const Point2f m0{draw.uniform(0.f, 200.f), draw.uniform(0.f, 200.f)};
      const Point2f s0{draw.uniform(0.f, 520.f), draw.uniform(0.f, 520.f)};
      for (int i = 0; i < 3; ++i) {
        const Point2f d{draw.uniform(-size, size), draw.uniform(-size, size)};
        model[i] = {m0.x + d.x, m0.y + d.y};
        scene[i] = {s0.x + zoom * (d.x + draw.uniform(-3.f, 3.f)),
                    s0.y + zoom * (d.y + draw.uniform(-3.f, 3.f))};
      }
      out.push_back(triangle_patch_correlation(looks[t % 2], window, model, scene));
    }
    return out;
  };
  const SimdLevel chosen = simd_level();
  std::printf("dispatched level: %s\n", simd_level_name(chosen));
  const std::vector<TrianglePatch> dispatched = run();
  set_simd_level(SimdLevel::kScalar);
  const std::vector<TrianglePatch> baseline = run();
  set_simd_level(SimdLevel::kAvx2);
  EXPECT_EQ(simd_level(), chosen);  // restored
  ASSERT_EQ(dispatched.size(), baseline.size());
  int measured = 0, mismatches = 0;
  for (std::size_t i = 0; i < baseline.size(); ++i) {
    measured += baseline[i].measured ? 1 : 0;
    if (dispatched[i].measured != baseline[i].measured ||
        std::memcmp(&dispatched[i].correlation, &baseline[i].correlation, sizeof(float)) != 0)
      ++mismatches;
  }
  std::printf("%d of %zu triangle pairs measured\n", measured, baseline.size());
  EXPECT_EQ(mismatches, 0);
  // Enough of both kinds that the comparison means something.
  EXPECT_GT(measured, 400);
  EXPECT_LT(measured, 2700);
}

TEST_F(TrianglePatchTest, AllocatesNothing) {
  const ModelAppearance look = look_of(model_, 1.f);
  const Point2f model[3] = {{60.f, 60.f}, {110.f, 72.f}, {82.f, 120.f}};
  const Point2f scene[3] = {warp(model[0]), warp(model[1]), warp(model[2])};
  test::AllocationCounter counter;
  const TrianglePatch right = check(look, model, scene);
  EXPECT_EQ(counter.count(), 0);
  EXPECT_TRUE(right.measured);
}

}  // namespace
}  // namespace kg
