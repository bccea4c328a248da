// Arc descriptors on real images: invariances the paper claims (brightness,
// contrast, rotation), the Bresenham sampling contract, and the DFT.
#include "core/description/arc_descriptor.h"
#include "core/description/descriptor_encoding.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
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

constexpr double kPi = 3.14159265358979323846;

struct Arc {
  Point2f a;
  Point2f b;
};

cv::Mat load(const char* name) {
  cv::Mat img = test::load_gray(test::opencv_data(name));
  EXPECT_FALSE(img.empty()) << name;
  return img;
}

// Random arcs with integer endpoints at least `margin` px inside the image
// and Chebyshev length in [min_len, max_len]. mt19937 output is specified by
// the standard, so the arcs are the same on every platform.
std::vector<Arc> random_arcs(int width, int height, int count, int margin, unsigned seed,
                             int min_len = 10, int max_len = 100) {
  std::mt19937 rng(seed);
  auto uniform = [&](int lo, int hi) { return lo + static_cast<int>(rng() % (hi - lo + 1)); };
  std::vector<Arc> arcs;
  while (static_cast<int>(arcs.size()) < count) {
    const int ax = uniform(margin, width - 1 - margin);
    const int ay = uniform(margin, height - 1 - margin);
    const int bx = ax + uniform(-max_len, max_len);
    const int by = ay + uniform(-max_len, max_len);
    const int cheb = std::max(std::abs(bx - ax), std::abs(by - ay));
    if (cheb < min_len || cheb > max_len) continue;
    if (bx < margin || by < margin || bx > width - 1 - margin || by > height - 1 - margin) continue;
    arcs.push_back({{static_cast<float>(ax), static_cast<float>(ay)},
                    {static_cast<float>(bx), static_cast<float>(by)}});
  }
  return arcs;
}

float distance(const ArcDescriptor& p, const ArcDescriptor& q) {
  return std::sqrt(squared_distance(p, q));
}

float max_abs_diff(const ArcDescriptor& p, const ArcDescriptor& q) {
  float m = 0.f;
  for (int i = 0; i < kDescriptorSize; ++i) m = std::max(m, std::fabs(p[i] - q[i]));
  return m;
}

// Exactly half-way ties at the segment midpoint are the one place where the
// sampled pixels depend on the orientation of the image (see the .cpp).
bool has_midpoint_tie(const Arc& arc) {
  const int dx = std::abs(static_cast<int>(arc.b.x - arc.a.x));
  const int dy = std::abs(static_cast<int>(arc.b.y - arc.a.y));
  const int d = std::max(dx, dy);
  const int dm = std::min(dx, dy);
  return d % 2 == 0 && dm % 2 == 1;
}

bool is_diagonal(const Arc& arc) {
  return std::abs(arc.b.x - arc.a.x) == std::abs(arc.b.y - arc.a.y);
}

struct Stats {
  int count = 0;
  double sum = 0.0;
  float max = 0.f;
  void add(float v) {
    ++count;
    sum += v;
    max = std::max(max, v);
  }
  double mean() const { return count ? sum / count : 0.0; }
};

// Reference Bresenham written from the contract, independent of the
// incremental version: minor coordinate = a + t*dm/d rounded to nearest,
// ties toward the nearer endpoint, the midpoint tie toward the smaller
// coordinate.
std::vector<cv::Point> reference_line(cv::Point a, cv::Point b) {
  const int dx = b.x - a.x, dy = b.y - a.y;
  const bool x_major = std::abs(dx) > std::abs(dy);
  const int d = std::max(std::abs(dx), std::abs(dy));
  const int am = x_major ? a.y : a.x;
  const int dm = x_major ? dy : dx;
  const int sM = (x_major ? dx : dy) >= 0 ? 1 : -1;
  std::vector<cv::Point> pts;
  for (int t = 0; t <= d; ++t) {
    // minor = am + t*dm/d; candidates floor and floor+1 of that rational.
    const long num = static_cast<long>(2) * t * dm + d;  // 2*(t*dm/d + 1/2) * d
    const long den = 2L * d;
    long fl = num / den;
    if (num % den != 0 && num < 0) --fl;    // floor division
    int minor = am + static_cast<int>(fl);  // round half up
    if (num % den == 0) {
      // ideal is minor - 0.5: choose minor-1 or minor.
      const int toward_a = dm > 0 ? minor - 1 : minor;
      const int toward_b = dm > 0 ? minor : minor - 1;
      if (2 * t < d)
        minor = toward_a;
      else if (2 * t > d)
        minor = toward_b;
      else
        minor = minor - 1;  // smaller coordinate
    }
    const int major = (x_major ? a.x : a.y) + sM * t;
    pts.push_back(x_major ? cv::Point(major, minor) : cv::Point(minor, major));
  }
  return pts;
}

// ---------------------------------------------------------------------------
// Sampling contract.

TEST(MeanProfile, MatchesReferenceBresenhamAndParallelShift) {
  const cv::Mat img = test::descriptor_blurred(load("graf1.png"));
  ASSERT_FALSE(img.empty());
  std::vector<Arc> arcs = random_arcs(img.cols, img.rows, 500, 3, 11);
  // Arcs with ties away from and at the midpoint, in every direction.
  for (const cv::Point& v : {cv::Point(10, 3), cv::Point(12, 2), cv::Point(-12, 2),
                             cv::Point(3, -10), cv::Point(-2, -12), cv::Point(20, 20),
                             cv::Point(-14, 7), cv::Point(30, 0), cv::Point(0, -30)}) {
    arcs.push_back(
        {{200.f, 200.f}, {static_cast<float>(200 + v.x), static_cast<float>(200 + v.y)}});
  }
  std::vector<float> profile, central;
  for (const Arc& arc : arcs) {
    const cv::Point a(static_cast<int>(arc.a.x), static_cast<int>(arc.a.y));
    const cv::Point b(static_cast<int>(arc.b.x), static_cast<int>(arc.b.y));
    const std::vector<cv::Point> line = reference_line(a, b);
    const bool x_major = std::abs(b.x - a.x) > std::abs(b.y - a.y);
    const cv::Point shift = x_major ? cv::Point(0, 2) : cv::Point(2, 0);
    ASSERT_TRUE(mean_profile(test::view(img), arc.a, arc.b, 0, central));
    ASSERT_TRUE(mean_profile(test::view(img), arc.a, arc.b, 2, profile));
    ASSERT_EQ(profile.size(),
              static_cast<std::size_t>(std::max(std::abs(b.x - a.x), std::abs(b.y - a.y)) + 1));
    ASSERT_EQ(profile.size(), line.size());
    for (std::size_t t = 0; t < line.size(); ++t) {
      const cv::Point p = line[t];
      ASSERT_FLOAT_EQ(central[t], img.at<std::uint8_t>(p));
      const int sum = img.at<std::uint8_t>(p) + img.at<std::uint8_t>(p + shift) +
                      img.at<std::uint8_t>(p - shift);
      ASSERT_FLOAT_EQ(profile[t], static_cast<float>(sum) / 3.f) << "t=" << t;
    }
  }
}

TEST(MeanProfile, AgreesWithOpenCvLineIteratorAwayFromTies) {
  // cv::LineIterator is an independent Bresenham; off exact half-way ties
  // every Bresenham visits the same pixels.
  const cv::Mat img = test::descriptor_blurred(load("box.png"));
  ASSERT_FALSE(img.empty());
  int compared = 0;
  std::vector<float> central;
  for (const Arc& arc : random_arcs(img.cols, img.rows, 400, 0, 12)) {
    const cv::Point a(static_cast<int>(arc.a.x), static_cast<int>(arc.a.y));
    const cv::Point b(static_cast<int>(arc.b.x), static_cast<int>(arc.b.y));
    const std::vector<cv::Point> ref = reference_line(a, b);
    bool tie = false;
    const int d = std::max(std::abs(b.x - a.x), std::abs(b.y - a.y));
    const int dm = std::min(std::abs(b.x - a.x), std::abs(b.y - a.y));
    for (int t = 0; t <= d; ++t) tie = tie || (2L * t * dm + d) % (2L * d) == 0;
    if (tie) continue;
    ASSERT_TRUE(mean_profile(test::view(img), arc.a, arc.b, 0, central));
    cv::LineIterator it(img, a, b, 8);
    ASSERT_EQ(it.count, static_cast<int>(central.size()));
    for (int t = 0; t < it.count; ++t, ++it) ASSERT_FLOAT_EQ(central[t], **it) << t;
    ++compared;
  }
  EXPECT_GT(compared, 100);
}

TEST(MeanProfile, RoundsEndpointsToNearestPixel) {
  const cv::Mat img = test::descriptor_blurred(load("box.png"));
  ASSERT_FALSE(img.empty());
  std::vector<float> p, q;
  ASSERT_TRUE(mean_profile(test::view(img), {40.4f, 50.6f}, {90.49f, 71.2f}, 1, p));
  ASSERT_TRUE(mean_profile(test::view(img), {40.f, 51.f}, {90.f, 71.f}, 1, q));
  EXPECT_EQ(p, q);
}

TEST(MeanProfile, RejectsOutsideAndDegenerateArcs) {
  const cv::Mat img = test::descriptor_blurred(load("box.png"));
  ASSERT_FALSE(img.empty());
  const ImageView v = test::view(img);
  const float w = static_cast<float>(img.cols), h = static_cast<float>(img.rows);
  std::vector<float> p;
  // Endpoints outside.
  EXPECT_FALSE(mean_profile(v, {-1.f, 10.f}, {30.f, 10.f}, 1, p));
  EXPECT_FALSE(mean_profile(v, {10.f, 10.f}, {w, 40.f}, 1, p));
  EXPECT_FALSE(mean_profile(v, {10.f, 10.f}, {40.f, h - 0.4f}, 1, p));
  EXPECT_FALSE(mean_profile(v, {NAN, 10.f}, {40.f, 10.f}, 1, p));
  EXPECT_FALSE(mean_profile(v, {1e30f, 10.f}, {40.f, 10.f}, 1, p));
  // Central line inside, a parallel one outside: horizontal on row 0, vertical
  // on the last column.
  EXPECT_FALSE(mean_profile(v, {10.f, 0.f}, {40.f, 3.f}, 1, p));
  EXPECT_TRUE(mean_profile(v, {10.f, 1.f}, {40.f, 3.f}, 1, p));
  EXPECT_TRUE(mean_profile(v, {10.f, 0.f}, {40.f, 3.f}, 0, p));
  EXPECT_FALSE(mean_profile(v, {w - 1.f, 10.f}, {w - 4.f, 50.f}, 1, p));
  EXPECT_TRUE(mean_profile(v, {w - 2.f, 10.f}, {w - 4.f, 50.f}, 1, p));
  EXPECT_FALSE(mean_profile(v, {w - 2.f, 10.f}, {w - 4.f, 50.f}, 2, p));
  // Same pixel after rounding.
  EXPECT_FALSE(mean_profile(v, {50.2f, 60.3f}, {49.6f, 59.8f}, 1, p));
  EXPECT_FALSE(mean_profile(ImageView(), {1.f, 1.f}, {5.f, 5.f}, 0, p));

  DescriptorParams params;
  ArcDescriptor d;
  EXPECT_FALSE(arc_descriptor(v, {10.f, 0.f}, {40.f, 3.f}, params, p, d));
  EXPECT_TRUE(arc_descriptor(v, {10.f, 1.f}, {40.f, 3.f}, params, p, d));
}

TEST(ResampleLinear, InterpolatesAndKeepsEnds) {
  const float two[] = {0.f, 10.f};
  float out[5];
  resample_linear(two, 2, out, 5);
  const float expected[] = {0.f, 2.5f, 5.f, 7.5f, 10.f};
  for (int i = 0; i < 5; ++i) EXPECT_FLOAT_EQ(out[i], expected[i]);

  // n > length: samples at i*(n-1)/(length-1) of a ramp reproduce the ramp.
  std::vector<float> ramp(101);
  for (int i = 0; i <= 100; ++i) ramp[i] = 3.f * static_cast<float>(i) + 7.f;
  float r[30];
  resample_linear(ramp.data(), 101, r, 30);
  for (int i = 0; i < 30; ++i) EXPECT_NEAR(r[i], 300.0 * i / 29.0 + 7.0, 1e-4) << i;
  EXPECT_EQ(r[0], ramp[0]);
  EXPECT_EQ(r[29], ramp[100]);

  // Same length: identity.
  float same[30];
  resample_linear(r, 30, same, 30);
  for (int i = 0; i < 30; ++i) EXPECT_EQ(same[i], r[i]);
}

// ---------------------------------------------------------------------------
// DFT and normalisation.

TEST(DescriptorFromProfile, CosineHasEnergyOnlyInItsCoefficient) {
  for (int length : {30, 17, 64, 256}) {
    for (int k = 1; k <= kMaxCoefficients; ++k) {
      const double phase = 0.7 * k - 1.1;
      std::vector<float> f(length);
      for (int y = 0; y < length; ++y)
        f[y] = static_cast<float>(120.0 + 40.0 * std::cos(2.0 * kPi * k * y / length + phase));
      ArcDescriptor d;
      ASSERT_TRUE(descriptor_from_profile(f.data(), length, 3, d));
      // F(k) = 40 * l/2 * exp(i phase): after normalisation (cos, sin).
      for (int x = 1; x <= kMaxCoefficients; ++x) {
        const float want_re = x == k ? static_cast<float>(std::cos(phase)) : 0.f;
        const float want_im = x == k ? static_cast<float>(std::sin(phase)) : 0.f;
        EXPECT_NEAR(d[2 * x - 2], want_re, 1e-5f) << "l=" << length << " k=" << k << " x=" << x;
        EXPECT_NEAR(d[2 * x - 1], want_im, 1e-5f) << "l=" << length << " k=" << k << " x=" << x;
      }
    }
  }
}

TEST(DescriptorFromProfile, UnitNormAndUnusedComponentsZero) {
  const cv::Mat img = test::descriptor_blurred(load("graf1.png"));
  ASSERT_FALSE(img.empty());
  std::vector<float> scratch;
  for (int m = 1; m <= kMaxCoefficients; ++m) {
    DescriptorParams params;
    params.coefficients = m;
    int ok = 0;
    for (const Arc& arc : random_arcs(img.cols, img.rows, 300, 2, 13)) {
      ArcDescriptor d;
      if (!arc_descriptor(test::view(img), arc.a, arc.b, params, scratch, d)) continue;
      ++ok;
      float norm2 = 0.f;
      for (float c : d) norm2 += c * c;
      EXPECT_NEAR(norm2, 1.f, 1e-5f);
      for (int i = 2 * m; i < kDescriptorSize; ++i) EXPECT_EQ(d[i], 0.f);
    }
    EXPECT_GT(ok, 290) << "m=" << m;
  }
}

TEST(DescriptorFromProfile, RejectsFlatProfilesButNotSmallSignals) {
  ArcDescriptor d;
  const std::vector<float> flat(30, 100.f);
  EXPECT_FALSE(descriptor_from_profile(flat.data(), 30, 3, d));
  // A constant that float cannot hold exactly, resampled (weights not
  // summing to exactly 1): still flat, not a descriptor of rounding noise.
  const std::vector<float> thirds(57, 301.f / 3.f);
  float r[30];
  resample_linear(thirds.data(), 57, r, 30);
  EXPECT_FALSE(descriptor_from_profile(r, 30, 3, d));
  const std::vector<float> zeros(17, 0.f);
  EXPECT_FALSE(descriptor_from_profile(zeros.data(), 17, 3, d));

  // Flat image region: rejected; one pixel of the central line one level
  // brighter (the smallest 8-bit change, 1/3 in the mean profile): accepted.
  cv::Mat img(80, 80, CV_8U, cv::Scalar(77));
  std::vector<float> scratch;
  const DescriptorParams params;
  EXPECT_FALSE(arc_descriptor(test::view(img), {10.f, 40.f}, {70.f, 40.f}, params, scratch, d));
  img.at<std::uint8_t>(40, 30) = 78;
  EXPECT_TRUE(arc_descriptor(test::view(img), {10.f, 40.f}, {70.f, 40.f}, params, scratch, d));
}

TEST(DescriptorFromProfile, RejectsBadSizes) {
  std::vector<float> f(300);
  for (std::size_t i = 0; i < f.size(); ++i) f[i] = static_cast<float>(i % 7);
  ArcDescriptor d;
  EXPECT_FALSE(descriptor_from_profile(f.data(), 1, 1, d));
  EXPECT_FALSE(descriptor_from_profile(f.data(), 257, 3, d));
  EXPECT_FALSE(descriptor_from_profile(f.data(), 30, 0, d));
  EXPECT_FALSE(descriptor_from_profile(f.data(), 30, kMaxCoefficients + 1, d));
  EXPECT_TRUE(descriptor_from_profile(f.data(), 256, 3, d));
  EXPECT_TRUE(descriptor_from_profile(f.data(), 2, 1, d));

  const cv::Mat img = test::descriptor_blurred(load("box.png"));
  ASSERT_FALSE(img.empty());
  std::vector<float> scratch;
  DescriptorParams params;
  params.profile_length = 257;
  EXPECT_FALSE(arc_descriptor(test::view(img), {10.f, 10.f}, {60.f, 30.f}, params, scratch, d));
  params.profile_length = 256;
  EXPECT_TRUE(arc_descriptor(test::view(img), {10.f, 10.f}, {60.f, 30.f}, params, scratch, d));
}

TEST(ArcDescriptor, ScratchStopsReallocating) {
  const cv::Mat img = test::descriptor_blurred(load("graf1.png"));
  ASSERT_FALSE(img.empty());
  std::vector<float> scratch;
  ArcDescriptor d;
  const DescriptorParams params;
  ASSERT_TRUE(arc_descriptor(test::view(img), {100.f, 100.f}, {200.f, 150.f}, params, scratch, d));
  const float* data = scratch.data();
  for (const Arc& arc : random_arcs(img.cols, img.rows, 200, 2, 14))
    arc_descriptor(test::view(img), arc.a, arc.b, params, scratch, d);
  EXPECT_EQ(scratch.data(), data);
}

// ---------------------------------------------------------------------------
// Reversal.

TEST(ArcDescriptor, ReversedArcIsReversedProfile) {
  const cv::Mat img = test::descriptor_blurred(load("graf1.png"));
  ASSERT_FALSE(img.empty());
  const DescriptorParams params;
  const int l = params.profile_length;
  std::vector<Arc> arcs = random_arcs(img.cols, img.rows, 500, 2, 15);
  for (const cv::Point& v : {cv::Point(10, 3), cv::Point(12, 2), cv::Point(-3, 14)})
    arcs.push_back(
        {{300.f, 300.f}, {static_cast<float>(300 + v.x), static_cast<float>(300 + v.y)}});
  std::vector<float> forward, backward, scratch;
  float max_direct = 0.f, max_analytic = 0.f;
  int ok = 0;
  for (const Arc& arc : arcs) {
    ASSERT_TRUE(mean_profile(test::view(img), arc.a, arc.b, params.parallel_offset, forward));
    ASSERT_TRUE(mean_profile(test::view(img), arc.b, arc.a, params.parallel_offset, backward));
    std::vector<float> reversed(forward.rbegin(), forward.rend());
    ASSERT_EQ(backward, reversed);  // same pixels, walked the other way

    ArcDescriptor fwd, bwd, direct;
    const bool ok_f = arc_descriptor(test::view(img), arc.a, arc.b, params, scratch, fwd);
    const bool ok_b = arc_descriptor(test::view(img), arc.b, arc.a, params, scratch, bwd);
    ASSERT_EQ(ok_f, ok_b);
    if (!ok_f) continue;
    ++ok;
    std::vector<float> r(l);
    resample_linear(reversed.data(), static_cast<int>(reversed.size()), r.data(), l);
    ASSERT_TRUE(descriptor_from_profile(r.data(), l, params.coefficients, direct));
    max_direct = std::max(max_direct, max_abs_diff(bwd, direct));

    // Analytically, reversing f gives F_rev(x) = exp(2 pi i x / l) conj F(x).
    ArcDescriptor analytic{};
    for (int x = 1; x <= params.coefficients; ++x) {
      const double re = fwd[2 * x - 2], im = -fwd[2 * x - 1];
      const double c = std::cos(2.0 * kPi * x / l), s = std::sin(2.0 * kPi * x / l);
      analytic[2 * x - 2] = static_cast<float>(c * re - s * im);
      analytic[2 * x - 1] = static_cast<float>(s * re + c * im);
    }
    max_analytic = std::max(max_analytic, max_abs_diff(bwd, analytic));
  }
  std::printf("reversal over %d arcs: max |diff| vs reversed profile %.3g, vs analytic %.3g\n", ok,
              max_direct, max_analytic);
  EXPECT_GT(ok, 490);
  EXPECT_LE(max_direct, 1e-5f);
  EXPECT_LE(max_analytic, 1e-5f);
}

// ---------------------------------------------------------------------------
// Photometric invariance. The change is applied to the blurred image, which
// is what the descriptor sees; images are first mapped into a range where
// the change cannot saturate.

TEST(ArcDescriptor, InvariantToBrightnessOffset) {
  for (const char* name : {"box.png", "graf1.png"}) {
    const cv::Mat raw = load(name);
    ASSERT_FALSE(raw.empty());
    cv::Mat scaled;
    raw.convertTo(scaled, CV_8U, 170.0 / 255.0, 30.0);  // [30, 200]
    const cv::Mat img = test::descriptor_blurred(scaled);
    cv::Mat brighter;
    img.convertTo(brighter, CV_8U, 1.0, 20.0);
    double lo, hi;
    cv::minMaxLoc(brighter, &lo, &hi);
    ASSERT_LT(hi, 255.0);
    std::vector<float> scratch;
    const DescriptorParams params;
    Stats diff;
    for (const Arc& arc : random_arcs(img.cols, img.rows, 1000, 2, 16)) {
      ArcDescriptor d0, d1;
      const bool ok0 = arc_descriptor(test::view(img), arc.a, arc.b, params, scratch, d0);
      const bool ok1 = arc_descriptor(test::view(brighter), arc.a, arc.b, params, scratch, d1);
      ASSERT_EQ(ok0, ok1);
      if (ok0) diff.add(max_abs_diff(d0, d1));
    }
    std::printf("%s brightness +20: %d arcs, max |diff| %.3g\n", name, diff.count, diff.max);
    EXPECT_GT(diff.count, 900);
    EXPECT_LE(diff.max, 1e-4f);
  }
}

TEST(ArcDescriptor, InvariantToContrastUpToRounding) {
  for (const char* name : {"box.png", "graf1.png"}) {
    const cv::Mat raw = load(name);
    ASSERT_FALSE(raw.empty());
    cv::Mat scaled;
    raw.convertTo(scaled, CV_8U, 130.0 / 255.0, 30.0);  // [30, 160]
    const cv::Mat img = test::descriptor_blurred(scaled);
    cv::Mat stronger;
    img.convertTo(stronger, CV_8U, 1.5, 0.0);  // rounds to 8 bits
    double lo, hi;
    cv::minMaxLoc(stronger, &lo, &hi);
    ASSERT_LT(hi, 255.0);
    std::vector<float> scratch;
    const DescriptorParams params;
    Stats dist;
    for (const Arc& arc : random_arcs(img.cols, img.rows, 1000, 2, 17)) {
      ArcDescriptor d0, d1;
      const bool ok0 = arc_descriptor(test::view(img), arc.a, arc.b, params, scratch, d0);
      const bool ok1 = arc_descriptor(test::view(stronger), arc.a, arc.b, params, scratch, d1);
      if (ok0 && ok1) dist.add(distance(d0, d1));
    }
    std::printf("%s contrast x1.5: %d arcs, mean distance %.4f, max %.4f\n", name, dist.count,
                dist.mean(), dist.max);
    EXPECT_GT(dist.count, 900);
    EXPECT_LT(dist.mean(), 0.02);
  }
}

// ---------------------------------------------------------------------------
// Rotation.

struct Rotation {
  int code;
  const char* name;
};

// Where pixel (x, y) of a w x h image goes under cv::rotate.
Point2f rotate_point(int code, Point2f p, int w, int h) {
  switch (code) {
    case cv::ROTATE_90_CLOCKWISE:
      return {static_cast<float>(h - 1) - p.y, p.x};
    case cv::ROTATE_180:
      return {static_cast<float>(w - 1) - p.x, static_cast<float>(h - 1) - p.y};
    default:  // ROTATE_90_COUNTERCLOCKWISE
      return {p.y, static_cast<float>(w - 1) - p.x};
  }
}

TEST(ArcDescriptor, RightAngleRotationsAreExactOffTies) {
  for (const char* name : {"box.png", "graf1.png"}) {
    const cv::Mat img = test::descriptor_blurred(load(name));
    ASSERT_FALSE(img.empty());
    const std::vector<Arc> arcs = random_arcs(img.cols, img.rows, 1000, 2, 18);
    for (const Rotation rot :
         {Rotation{cv::ROTATE_90_CLOCKWISE, "90"}, Rotation{cv::ROTATE_180, "180"},
          Rotation{cv::ROTATE_90_COUNTERCLOCKWISE, "270"}}) {
      cv::Mat rotated;
      cv::rotate(img, rotated, rot.code);
      // The mapping itself, on a few pixels.
      for (const Arc& arc : {arcs[0], arcs[1]}) {
        const Point2f q = rotate_point(rot.code, arc.a, img.cols, img.rows);
        ASSERT_EQ(img.at<std::uint8_t>(static_cast<int>(arc.a.y), static_cast<int>(arc.a.x)),
                  rotated.at<std::uint8_t>(static_cast<int>(q.y), static_cast<int>(q.x)));
      }
      const bool quarter = rot.code != cv::ROTATE_180;
      std::vector<float> scratch;
      const DescriptorParams params;
      Stats exact, rest;
      for (const Arc& arc : arcs) {
        ArcDescriptor d0, d1;
        const bool ok0 = arc_descriptor(test::view(img), arc.a, arc.b, params, scratch, d0);
        const bool ok1 =
            arc_descriptor(test::view(rotated), rotate_point(rot.code, arc.a, img.cols, img.rows),
                           rotate_point(rot.code, arc.b, img.cols, img.rows), params, scratch, d1);
        ASSERT_EQ(ok0, ok1);
        if (!ok0) continue;
        // Off midpoint ties (and, for quarter turns, off diagonals, whose
        // parallel profiles are x-shifted by definition) the sampled pixels
        // are the rotated ones.
        if (has_midpoint_tie(arc) || (quarter && is_diagonal(arc))) {
          rest.add(distance(d0, d1));
        } else {
          exact.add(distance(d0, d1));
        }
      }
      std::printf(
          "%s rot %s: %d exact-class arcs max %.3g; %d tie/diagonal arcs mean %.4f max %.4f\n",
          name, rot.name, exact.count, exact.max, rest.count, rest.mean(), rest.max);
      EXPECT_GT(exact.count, 500);
      EXPECT_EQ(exact.max, 0.f);
      // Measured: mean <= 0.0071, max <= 0.26 (one pixel moved in a profile).
      EXPECT_LT(rest.mean(), 0.015);
      EXPECT_LT(rest.max, 0.35f);
    }
  }
}

TEST(ArcDescriptor, ArbitraryRotationKeepsArcsSimilar) {
  const DescriptorParams params;
  for (const char* name : {"box.png", "graf1.png"}) {
    const cv::Mat raw = load(name);
    ASSERT_FALSE(raw.empty());
    // Rotate by 30 degrees about the centre onto a canvas holding all of it.
    const double angle = 30.0;
    const cv::Point2f centre(static_cast<float>(raw.cols - 1) / 2.f,
                             static_cast<float>(raw.rows - 1) / 2.f);
    cv::Mat m = cv::getRotationMatrix2D(centre, angle, 1.0);
    const cv::Rect2f box =
        cv::RotatedRect(centre, raw.size(), static_cast<float>(angle)).boundingRect2f();
    m.at<double>(0, 2) += box.width / 2.0 - centre.x;
    m.at<double>(1, 2) += box.height / 2.0 - centre.y;
    cv::Mat warped;
    cv::warpAffine(
        raw, warped, m,
        cv::Size(static_cast<int>(std::ceil(box.width)), static_cast<int>(std::ceil(box.height))),
        cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
    const cv::Mat img = test::descriptor_blurred(raw);
    const cv::Mat rotated = test::descriptor_blurred(warped);
    auto map = [&](Point2f p) {
      return Point2f{static_cast<float>(m.at<double>(0, 0) * p.x + m.at<double>(0, 1) * p.y +
                                        m.at<double>(0, 2)),
                     static_cast<float>(m.at<double>(1, 0) * p.x + m.at<double>(1, 1) * p.y +
                                        m.at<double>(1, 2))};
    };
    // Margin keeps the profiles clear of the black canvas the blur would mix in.
    const std::vector<Arc> arcs = random_arcs(img.cols, img.rows, 2000, 8, 19);
    std::vector<float> scratch;
    std::vector<ArcDescriptor> originals;
    Stats same;
    int similar = 0;  // pairs the selection step would accept
    for (const Arc& arc : arcs) {
      ArcDescriptor d0, d1;
      if (!arc_descriptor(test::view(img), arc.a, arc.b, params, scratch, d0)) continue;
      if (!arc_descriptor(test::view(rotated), map(arc.a), map(arc.b), params, scratch, d1))
        continue;
      same.add(distance(d0, d1));
      similar += distance(d0, d1) < params.similarity_threshold;
      originals.push_back(d0);
    }
    Stats unrelated;
    const std::size_t n = originals.size();
    for (std::size_t i = 0; i < n; ++i)
      unrelated.add(distance(originals[i], originals[(i + n / 2) % n]));
    std::printf(
        "%s rot 30: %d arcs, same arc mean distance %.4f (max %.3f, %.1f%% below threshold), "
        "unrelated arcs %.4f\n",
        name, same.count, same.mean(), same.max, 100.0 * similar / same.count, unrelated.mean());
    EXPECT_GT(same.count, 1900);
    // Measured: 0.093 (box), 0.064 (graf1) against 1.36 for unrelated arcs.
    EXPECT_LT(same.mean(), 0.5 * params.similarity_threshold);
    EXPECT_LT(same.mean(), 0.1 * unrelated.mean());
  }
}

// The fixed-point descriptor is the float one quantised, computed without
// the float rounding in between: on thousands of real arcs each component
// differs from quantise(float descriptor) by at most one step (int8 and
// int16), and almost all are equal.
TEST(FixedPointDescriptor, AgreesWithQuantisedFloat) {
  const cv::Mat img = test::descriptor_blurred(load("graf1.png"));
  const ImageView v = test::view(img);
  const std::vector<Arc> arcs = random_arcs(img.cols, img.rows, 4000, 4, 21);
  DescriptorParams params;
  for (const DescriptorEncoding e : {DescriptorEncoding::kInt8, DescriptorEncoding::kInt16}) {
    params.encoding = e;
    ASSERT_TRUE(uses_fixed_point(params));
    const std::int32_t scale = encoding_scale(e);
    std::vector<float> profile;
    std::vector<std::int32_t> sums;
    int described = 0, equal_components = 0, off_by_one = 0, both_flat = 0;
    for (const Arc& arc : arcs) {
      ArcDescriptor d;
      std::int32_t q[kDescriptorSize];
      const bool f = arc_descriptor(v, arc.a, arc.b, params, profile, d);
      const bool x = arc_descriptor_fixed(v, arc.a, arc.b, params, scale, sums, q);
      if (!f && !x) {
        ++both_flat;
        continue;
      }
      ASSERT_EQ(f, x) << "one path found the profile flat, the other not";
      ++described;
      for (int i = 0; i < kDescriptorSize; ++i) {
        const double want = std::round(static_cast<double>(d[i]) * scale);
        const double diff = std::fabs(want - q[i]);
        ASSERT_LE(diff, 1.0) << "component " << i;
        equal_components += diff == 0.0 ? 1 : 0;
        off_by_one += diff == 1.0 ? 1 : 0;
      }
    }
    ASSERT_GT(described, 3000);
    const double equal = static_cast<double>(equal_components) / (described * kDescriptorSize);
    std::printf("%s: %d arcs, %.2f %% of components equal, %d off by one step\n", encoding_name(e),
                described, 100.0 * equal, off_by_one);
    EXPECT_GE(equal, e == DescriptorEncoding::kInt8 ? 0.999 : 0.99);
  }
}

TEST(FixedPointDescriptor, ResamplingIsExactlyScaledFloat) {
  std::vector<std::int32_t> in = {0, 3, 9, 765, 42, 7, 100, 512, 1, 0, 300, 299, 298};
  std::vector<float> fin(in.begin(), in.end());
  for (int length : {2, 5, 30}) {
    std::vector<std::int32_t> out(static_cast<std::size_t>(length));
    std::vector<float> fout(static_cast<std::size_t>(length));
    resample_linear_fixed(in.data(), static_cast<int>(in.size()), out.data(), length);
    resample_linear(fin.data(), static_cast<int>(fin.size()), fout.data(), length);
    for (int i = 0; i < length; ++i)
      EXPECT_NEAR(out[static_cast<std::size_t>(i)] / static_cast<double>(length - 1),
                  fout[static_cast<std::size_t>(i)], 1e-3);
  }
  // A constant profile is flat; a brightness offset changes nothing.
  std::vector<std::int32_t> flat(30, 300), out(kDescriptorSize);
  EXPECT_FALSE(fixed_descriptor(flat.data(), 30, 3, 127, out.data()));
  std::vector<std::int32_t> ramp(30), shifted(30), a(kDescriptorSize), b(kDescriptorSize);
  for (int y = 0; y < 30; ++y) {
    ramp[static_cast<std::size_t>(y)] = 10 * y;
    shifted[static_cast<std::size_t>(y)] = 10 * y + 333;
  }
  ASSERT_TRUE(fixed_descriptor(ramp.data(), 30, 3, 127, a.data()));
  ASSERT_TRUE(fixed_descriptor(shifted.data(), 30, 3, 127, b.data()));
  EXPECT_EQ(a, b);
}

// The direct computations that resample_linear_fixed() and
// fixed_descriptor() shortened (a branch-free walk; the DFT folded on the
// table's symmetry, every coefficient in one pass): the walk with its
// branches, and the 30-term DFT with Q28 tables as the function documents.
void direct_resample(const std::int32_t* in, int n, std::int32_t* out, int length) {
  const int last = length - 1;
  const int step = (n - 1) / last;
  const int step_rem = (n - 1) % last;
  int j = 0;
  int r = 0;
  for (int i = 0; i < length; ++i) {
    out[i] = r == 0 ? in[j] * last : in[j] * (last - r) + in[j + 1] * r;
    j += step;
    r += step_rem;
    if (r >= last) {
      r -= last;
      ++j;
    }
  }
}

bool direct_fixed_descriptor(const std::int32_t* profile, int coefficients, std::int32_t scale,
                             std::int32_t* out) {
  constexpr int kL = 30;
  constexpr double kTwoPi = 6.283185307179586476925286766559;
  for (int i = 0; i < kDescriptorSize; ++i) out[i] = 0;
  std::int64_t sum = 0;
  for (int y = 0; y < kL; ++y) sum += profile[y];
  std::int64_t c[kDescriptorSize];
  std::uint64_t largest = 0;
  for (int x = 0; x < coefficients; ++x) {
    std::int64_t re = 0, im = 0;
    for (int y = 0; y < kL; ++y) {
      const double angle = kTwoPi * ((x + 1) * y % kL) / kL;
      const std::int64_t dev = std::int64_t{profile[y]} * kL - sum;
      re += dev * std::lround(std::cos(angle) * 268435456.0);
      im -= dev * std::lround(std::sin(angle) * 268435456.0);
    }
    c[2 * x] = re;
    c[2 * x + 1] = im;
    largest = std::max({largest, static_cast<std::uint64_t>(std::llabs(re)),
                        static_cast<std::uint64_t>(std::llabs(im))});
  }
  if (largest == 0) return false;
  int bits = 0;
  while ((largest >> bits) != 0) ++bits;
  const int shift = std::max(0, bits - 30);
  std::uint64_t energy = 0;
  for (int i = 0; i < 2 * coefficients; ++i) {
    c[i] >>= shift;
    energy += static_cast<std::uint64_t>(c[i] * c[i]);
  }
  auto norm = static_cast<std::int64_t>(std::sqrt(static_cast<double>(energy)));
  while (static_cast<std::uint64_t>(norm * norm) > energy) --norm;
  while (static_cast<std::uint64_t>((norm + 1) * (norm + 1)) <= energy) ++norm;
  if (norm == 0) return false;
  for (int i = 0; i < 2 * coefficients; ++i) {
    const std::int64_t q =
        std::min<std::int64_t>(scale, (2 * scale * std::llabs(c[i]) + norm) / (2 * norm));
    out[i] = static_cast<std::int32_t>(c[i] < 0 ? -q : q);
  }
  return true;
}

// On the profiles of thousands of real arcs (graf1 and box, blurred as the
// scene is), the resampling and the descriptor equal the direct
// computations exactly, for every coefficient count and both encodings;
// and resampling to other lengths, shorter and longer than the profile.
TEST(FixedPointDescriptor, EqualsTheDirectComputationOnRealArcs) {
  DescriptorParams params;
  int compared = 0;
  for (const char* name : {"graf1.png", "box.png"}) {
    const cv::Mat img = test::descriptor_blurred(load(name));
    const ImageView v = test::view(img);
    for (const Arc& arc : random_arcs(img.cols, img.rows, 3000, 4, 23, 4, 160)) {
      const int n = profile_samples(v, arc.a, arc.b, params.parallel_offset);
      if (n < 2) continue;
      std::vector<std::int32_t> sums(static_cast<std::size_t>(n));
      ASSERT_TRUE(profile_sums(v, arc.a, arc.b, params.parallel_offset, sums.data()));
      for (int length : {2, 3, 7, 30, 41, 200}) {
        std::vector<std::int32_t> got(static_cast<std::size_t>(length), -1);
        std::vector<std::int32_t> want(static_cast<std::size_t>(length), -2);
        resample_linear_fixed(sums.data(), n, got.data(), length);
        direct_resample(sums.data(), n, want.data(), length);
        ASSERT_EQ(got, want) << name << " n " << n << " length " << length;
      }
      std::int32_t profile[30];
      resample_linear_fixed(sums.data(), n, profile, 30);
      for (int coefficients = 1; coefficients <= kMaxCoefficients; ++coefficients) {
        for (const std::int32_t scale : {127, 32767}) {
          std::int32_t got[kDescriptorSize], want[kDescriptorSize];
          const bool g = fixed_descriptor(profile, 30, coefficients, scale, got);
          ASSERT_EQ(g, direct_fixed_descriptor(profile, coefficients, scale, want));
          for (int i = 0; i < kDescriptorSize; ++i)
            ASSERT_EQ(got[i], want[i]) << name << " component " << i;
          compared += g ? 1 : 0;
        }
      }
    }
  }
  EXPECT_GT(compared, 30000);
}

}  // namespace
}  // namespace kg
