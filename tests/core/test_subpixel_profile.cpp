// Sub-pixel arc profiles (DescriptorParams::subpixel_profiles, issue 38):
// exact samples on a ramp, exact reversal, the fixed-point and float paths
// alike, and what they are for: a short arc whose keypoints move by a
// fraction of a pixel with the image keeps its descriptor better than the
// Bresenham line between rounded ends does.
#include "core/description/arc_descriptor.h"
#include "core/description/descriptor_encoding.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/description/arc_types.h"
#include "core/image/blur.h"
#include "core/image/plane.h"
#include "support/descriptor_blur.h"
#include "support/test_data.h"

namespace kg {
namespace {

DescriptorParams subpixel_params() {
  DescriptorParams p;
  p.subpixel_profiles = 1;
  return p;
}

float distance(const ArcDescriptor& p, const ArcDescriptor& q) {
  return std::sqrt(squared_distance(p, q));
}

// A ramp 4 x: bilinear samples of a linear image are exact, so every
// sample is 3 lines x 256 x 4 x at its position rounded to 1/16 pixel.
TEST(SubpixelProfile, SamplesARampExactlyAtSixteenthsOfAPixel) {
  cv::Mat ramp(40, 64, CV_8U);
  for (int y = 0; y < ramp.rows; ++y)
    for (int x = 0; x < ramp.cols; ++x)
      ramp.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(4 * x);
  const Point2f a{10.25f, 20.5f}, b{30.8f, 20.5f};  // b.x rounds to 30.8125
  std::vector<std::int32_t> out(30);
  ASSERT_TRUE(subpixel_profile(test::view(ramp), a, b, 1, 30, out.data()));
  const std::int64_t a16 = 164, b16 = 493;  // 10.25 and 30.8 in 1/16 pixel
  for (int i = 0; i < 30; ++i) {
    // a + (b - a) i / 29 rounded to 1/16, halves away from zero.
    const std::int64_t num = a16 * 29 + (b16 - a16) * i;
    const std::int64_t x16 = (2 * num + 29) / 58;
    EXPECT_EQ(out[static_cast<std::size_t>(i)], 3 * 4 * 16 * x16) << i;
  }
  // A vertical arc on the same ramp: the parallel lines at x -+ 1 average to
  // the centre's value, so the profile is flat.
  ASSERT_TRUE(subpixel_profile(test::view(ramp), {20.3f, 5.f}, {20.3f, 30.f}, 1, 30, out.data()));
  for (int i = 1; i < 30; ++i) EXPECT_EQ(out[static_cast<std::size_t>(i)], out[0]);
}

TEST(SubpixelProfile, ReversedArcIsTheReversedProfile) {
  const cv::Mat img = test::descriptor_blurred(test::load_gray(test::opencv_data("graf1.png")));
  ASSERT_FALSE(img.empty());
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> x(4.f, static_cast<float>(img.cols) - 5.f);
  std::uniform_real_distribution<float> y(4.f, static_cast<float>(img.rows) - 5.f);
  std::uniform_real_distribution<float> step(-20.f, 20.f);
  std::vector<std::int32_t> forward(30), backward(30);
  int checked = 0;
  for (int k = 0; k < 2000; ++k) {
    const Point2f a{x(rng), y(rng)};
    const Point2f b{a.x + step(rng), a.y + step(rng)};
    const bool f = subpixel_profile(test::view(img), a, b, 2, 30, forward.data());
    ASSERT_EQ(f, subpixel_profile(test::view(img), b, a, 2, 30, backward.data()));
    if (!f) continue;
    ++checked;
    for (int i = 0; i < 30; ++i)
      ASSERT_EQ(forward[static_cast<std::size_t>(i)], backward[static_cast<std::size_t>(29 - i)]);
  }
  EXPECT_GT(checked, 1900);
}

TEST(SubpixelProfile, RefusesArcsOutsideTheImageAndDegenerateOnes) {
  const cv::Mat img(20, 30, CV_8U, cv::Scalar(7));
  std::vector<std::int32_t> out(30);
  const ImageView v = test::view(img);
  EXPECT_TRUE(subpixel_profile(v, {1.f, 1.f}, {28.f, 18.f}, 0, 30, out.data()));
  // The parallel lines need a pixel more on each side.
  EXPECT_FALSE(subpixel_profile(v, {1.f, 0.5f}, {28.f, 0.5f}, 1, 30, out.data()));
  EXPECT_TRUE(subpixel_profile(v, {1.f, 1.f}, {28.f, 1.f}, 1, 30, out.data()));
  // Bilinear samples need the pixel to the right and below: x = 28.5 is
  // inside a 30 pixel wide image, x = 29 (the last pixel's centre) is not.
  EXPECT_TRUE(subpixel_profile(v, {1.f, 1.f}, {28.5f, 1.f}, 1, 30, out.data()));
  EXPECT_FALSE(subpixel_profile(v, {1.f, 1.f}, {29.f, 1.f}, 1, 30, out.data()));
  EXPECT_FALSE(subpixel_profile(v, {-0.5f, 5.f}, {10.f, 5.f}, 1, 30, out.data()));
  EXPECT_FALSE(subpixel_profile(v, {5.f, 5.f}, {5.01f, 5.f}, 1, 30, out.data()));  // one 1/16
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(subpixel_profile(v, {nan, 5.f}, {10.f, 5.f}, 1, 30, out.data()));
  EXPECT_FALSE(subpixel_profile(v, {5.f, 5.f}, {1e30f, 5.f}, 1, 30, out.data()));
  EXPECT_FALSE(subpixel_profile(v, {5.f, 5.f}, {10.f, 5.f}, 1, 1, out.data()));
  // A flat image gives a flat profile, which no descriptor describes.
  ArcDescriptor d;
  std::vector<float> scratch;
  EXPECT_FALSE(arc_descriptor(v, {3.f, 3.f}, {20.f, 12.f}, subpixel_params(), scratch, d));
}

// The integer encodings' descriptor is the float one quantised, as for the
// Bresenham profiles (FixedPointDescriptor.AgreesWithQuantisedFloat).
TEST(SubpixelProfile, FixedPointAgreesWithQuantisedFloat) {
  const cv::Mat img = test::descriptor_blurred(test::load_gray(test::opencv_data("box.png")));
  ASSERT_FALSE(img.empty());
  DescriptorParams params = subpixel_params();
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> x(3.f, static_cast<float>(img.cols) - 4.f);
  std::uniform_real_distribution<float> y(3.f, static_cast<float>(img.rows) - 4.f);
  std::uniform_real_distribution<float> step(-40.f, 40.f);
  for (const DescriptorEncoding e : {DescriptorEncoding::kInt8, DescriptorEncoding::kInt16}) {
    params.encoding = e;
    const std::int32_t scale = encoding_scale(e);
    std::vector<float> profile;
    std::vector<std::int32_t> sums;
    int described = 0, equal = 0;
    for (int k = 0; k < 3000; ++k) {
      const Point2f a{x(rng), y(rng)};
      const Point2f b{a.x + step(rng), a.y + step(rng)};
      ArcDescriptor d;
      std::int32_t q[kDescriptorSize];
      const bool f = arc_descriptor(test::view(img), a, b, params, profile, d);
      ASSERT_EQ(f, arc_descriptor_fixed(test::view(img), a, b, params, scale, sums, q));
      if (!f) continue;
      ++described;
      for (int i = 0; i < kDescriptorSize; ++i) {
        const double diff = std::fabs(std::round(static_cast<double>(d[i]) * scale) - q[i]);
        ASSERT_LE(diff, 1.0);
        equal += diff == 0.0;
      }
    }
    EXPECT_GT(described, 2000);
    EXPECT_GE(static_cast<double>(equal) / (described * kDescriptorSize), 0.99);
  }
}

// Short arcs (7 to 12 pixels, as between a small sign's keypoints) in a
// real image and in the image moved by a fraction of a pixel, their ends
// moved with it: the sub-pixel profile follows the move, the Bresenham
// line between rounded ends jumps by whole pixels.
TEST(SubpixelProfile, ShortArcsFollowASubpixelMove) {
  for (const char* name : {"box.png", "graf1.png"}) {
    const cv::Mat raw = test::load_gray(test::opencv_data(name));
    ASSERT_FALSE(raw.empty());
    const double tx = 0.4, ty = -0.3;
    const cv::Matx23d move(1, 0, tx, 0, 1, ty);
    cv::Mat moved;
    cv::warpAffine(raw, moved, move, raw.size(), cv::INTER_CUBIC, cv::BORDER_REPLICATE);
    const cv::Mat img = test::descriptor_blurred(raw), img2 = test::descriptor_blurred(moved);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> x(10.f, static_cast<float>(img.cols) - 11.f);
    std::uniform_real_distribution<float> y(10.f, static_cast<float>(img.rows) - 11.f);
    std::uniform_real_distribution<float> angle(0.f, 6.2831853f), length(7.f, 12.f);
    double sum[2] = {0.0, 0.0};
    int n = 0;
    std::vector<std::int32_t> sums;
    for (int k = 0; k < 3000; ++k) {
      const Point2f a{x(rng), y(rng)};
      const float t = angle(rng), l = length(rng);
      const Point2f b{a.x + l * std::cos(t), a.y + l * std::sin(t)};
      const Point2f a2{a.x + static_cast<float>(tx), a.y + static_cast<float>(ty)};
      const Point2f b2{b.x + static_cast<float>(tx), b.y + static_cast<float>(ty)};
      double d[2];
      bool ok = true;
      for (int s = 0; s < 2 && ok; ++s) {
        DescriptorParams p;
        p.subpixel_profiles = s;
        std::int32_t q0[kDescriptorSize], q1[kDescriptorSize];
        ok = arc_descriptor_fixed(test::view(img), a, b, p, 127, sums, q0) &&
             arc_descriptor_fixed(test::view(img2), a2, b2, p, 127, sums, q1);
        ArcDescriptor f0, f1;
        for (int i = 0; i < kDescriptorSize; ++i) {
          f0[i] = static_cast<float>(q0[i]) / 127.f;
          f1[i] = static_cast<float>(q1[i]) / 127.f;
        }
        d[s] = distance(f0, f1);
      }
      if (!ok) continue;
      sum[0] += d[0];
      sum[1] += d[1];
      ++n;
    }
    ASSERT_GT(n, 2500);
    const double bresenham = sum[0] / n, subpixel = sum[1] / n;
    std::printf(
        "%s, arcs of 7-12 px moved by (%.1f, %.1f) px: mean distance %.4f Bresenham, "
        "%.4f sub-pixel\n",
        name, tx, ty, bresenham, subpixel);
    EXPECT_LT(subpixel, 0.6 * bresenham);
  }
}

}  // namespace
}  // namespace kg
