// Scene keypoint sampling: a maximal Chebyshev-separated subset.
#include <gtest/gtest.h>

#include <vector>

#include "core/sampling/sampling.h"
#include "core/support/rng.h"

namespace kg {
namespace {

std::vector<Keypoint> random_keypoints(Rng& rng, int n, float w, float h) {
  std::vector<Keypoint> k(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    k[i].x = static_cast<float>(rng.uniform01() * w);
    k[i].y = static_cast<float>(rng.uniform01() * h);
    k[i].response = static_cast<float>(n - i);
  }
  return k;
}

void expect_separated_and_maximal(const std::vector<Keypoint>& k, const std::vector<int>& sel,
                                  float d) {
  std::vector<bool> chosen(k.size(), false);
  for (int i : sel) chosen[i] = true;
  for (std::size_t a = 0; a < sel.size(); ++a) {
    for (std::size_t b = a + 1; b < sel.size(); ++b) {
      const Point2f p{k[sel[a]].x, k[sel[a]].y}, q{k[sel[b]].x, k[sel[b]].y};
      ASSERT_GE(chebyshev(p, q), d);
    }
  }
  // Maximal: every unchosen keypoint has a chosen one closer than d.
  for (std::size_t i = 0; i < k.size(); ++i) {
    if (chosen[i]) continue;
    bool blocked = false;
    for (int j : sel) blocked = blocked || chebyshev({k[i].x, k[i].y}, {k[j].x, k[j].y}) < d;
    ASSERT_TRUE(blocked) << "keypoint " << i << " could have been added";
  }
}

TEST(Sampling, RandomSubsetIsSeparatedAndMaximal) {
  Rng data(1);
  const auto k = random_keypoints(data, 3000, 640.f, 480.f);
  SeparatedSampler sampler;
  std::vector<int> sel;
  for (float d : {3.f, 10.f, 25.f}) {
    Rng rng(42);
    sampler.sample(k.data(), static_cast<int>(k.size()), d, &rng, sel);
    expect_separated_and_maximal(k, sel, d);
  }
}

TEST(Sampling, SeedDecidesTheSubset) {
  Rng data(2);
  const auto k = random_keypoints(data, 2000, 640.f, 480.f);
  SeparatedSampler sampler;
  std::vector<int> a, b, c;
  Rng r1(5), r2(5), r3(6);
  sampler.sample(k.data(), 2000, 10.f, &r1, a);
  sampler.sample(k.data(), 2000, 10.f, &r2, b);
  sampler.sample(k.data(), 2000, 10.f, &r3, c);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

TEST(Sampling, StrongestFirstKeepsTheFirstKeypoint) {
  Rng data(3);
  auto k = random_keypoints(data, 500, 200.f, 200.f);
  SeparatedSampler sampler;
  std::vector<int> sel;
  sampler.sample(k.data(), 500, 10.f, nullptr, sel);
  ASSERT_FALSE(sel.empty());
  EXPECT_EQ(sel[0], 0);
  expect_separated_and_maximal(k, sel, 10.f);
}

TEST(Sampling, ExactDistanceIsAllowed) {
  // Chebyshev distance exactly d is not "closer than d".
  std::vector<Keypoint> k(3);
  k[0] = {0.f, 0.f, 0.f, 3.f};
  k[1] = {10.f, 4.f, 0.f, 2.f};
  k[2] = {9.9f, 0.f, 0.f, 1.f};
  SeparatedSampler sampler;
  std::vector<int> sel;
  sampler.sample(k.data(), 3, 10.f, nullptr, sel);
  EXPECT_EQ(sel, (std::vector<int>{0, 1}));
}

}  // namespace
}  // namespace kg
