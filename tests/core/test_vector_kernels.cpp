// The vector loops and the keypoints' row bands, on the golden PGM frames
// (no OpenCV, so the ARM cross-builds run it under qemu):
// - the blur, the Hessian keypoints, the triangle patch correlations and
//   the appearance alignment's fit at the best SIMD level this CPU and
//   build have (AVX2 on x86-64, NEON on AArch64) equal the portable loops'
//   (kScalar), byte for byte;
// - the keypoints are the same, byte for byte, for 1 to 4 row bands on a
//   worker pool, also when the candidate cap is reached, and detecting with
//   workers allocates nothing once reserved.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "core/image/blur.h"
#include "core/keypoints/hessian.h"
#include "core/pose/appearance_align.h"
#include "core/pose/homography.h"
#include "core/selection/triangle_patch.h"
#include "core/support/worker_pool.h"
#include "keygraph/simd.h"
#include "platform/files/pgm.h"
#include "support/alloc_counter.h"
#include "support/simd_scope.h"

namespace kg {
namespace {

platform::GrayImage frame(const std::string& name) {
  platform::GrayImage image;
  const Status read = platform::read_pgm(KG_GOLDEN_FRAMES_DIR "/" + name, image);
  EXPECT_TRUE(read) << read.message();
  return image;
}

// The frames, and a crop of odd size whose rows do not start aligned.
struct Frames {
  platform::GrayImage box = frame("box.pgm");
  platform::GrayImage scene = frame("box_in_scene.pgm");
  std::vector<ImageView> views() const {
    const ImageView s = scene.view();
    return {box.view(), s,
            ImageView(s.row(37) + 13, s.width - 13 - 24, s.height - 37 - 50, s.stride)};
  }
};

const Frames& frames() {
  static const Frames f;
  return f;
}

bool same_bytes(const std::vector<Keypoint>& a, const std::vector<Keypoint>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Keypoint)) == 0);
}

// Keypoints on `bands` row bands (1: no pool), with the pipeline's caps.
bool detect_on(ImageView image, int bands, int max_candidates, std::vector<Keypoint>& out) {
  WorkerPool pool(bands);
  HessianDetector detector;
  detector.reserve(image.width, image.height, KeypointParams{}, 1500, max_candidates, bands);
  if (bands > 1) detector.set_workers(&pool);
  WorkVector<Keypoint> found;
  const bool complete = detector.detect(image, KeypointParams{}, 1500, found);
  out.assign(found.begin(), found.end());
  return complete;
}

TEST(KeypointBands, SameKeypointsForAnyBandCount) {
  for (const ImageView image : frames().views()) {
    ASSERT_FALSE(image.empty());
    std::vector<Keypoint> one;
    ASSERT_TRUE(detect_on(image, 1, 24000, one));
    ASSERT_GT(one.size(), 100u) << image.width << "x" << image.height;
    for (int bands = 2; bands <= 4; ++bands) {
      std::vector<Keypoint> many;
      EXPECT_TRUE(detect_on(image, bands, 24000, many));
      EXPECT_TRUE(same_bytes(one, many))
          << bands << " bands, " << image.width << "x" << image.height << ": " << many.size()
          << " keypoints against " << one.size();
    }
  }
}

// A cap the frame overflows keeps the first candidates in scan order,
// whichever band found them.
TEST(KeypointBands, CandidateCapCutsWhereOneBandWould) {
  const ImageView image = frames().scene.view();
  std::vector<Keypoint> uncapped, one;
  ASSERT_TRUE(detect_on(image, 1, 24000, uncapped));
  ASSERT_FALSE(detect_on(image, 1, 150, one));
  ASSERT_FALSE(one.empty());
  EXPECT_LT(one.size(), uncapped.size());
  for (int bands = 2; bands <= 4; ++bands) {
    std::vector<Keypoint> many;
    EXPECT_FALSE(detect_on(image, bands, 150, many));
    EXPECT_TRUE(same_bytes(one, many)) << bands << " bands";
  }
}

TEST(KeypointBands, NothingAllocatedPerFrameWithWorkers) {
  const ImageView image = frames().scene.view();
  WorkerPool pool(3);
  HessianDetector detector;
  detector.reserve(image.width, image.height, KeypointParams{}, 1500, 24000, 3);
  detector.set_workers(&pool);
  WorkVector<Keypoint> found;
  found.reserve(1500);
  ASSERT_TRUE(detector.detect(image, KeypointParams{}, 1500, found));
  const std::vector<Keypoint> first(found.begin(), found.end());
  const std::vector<ImageView> views = frames().views();
  const test::AllocationCounter counter;
  for (const ImageView v : views) detector.detect(v, KeypointParams{}, 1500, found);
  ASSERT_TRUE(detector.detect(image, KeypointParams{}, 1500, found));
  EXPECT_EQ(counter.count(), 0);
  EXPECT_TRUE(same_bytes(first, std::vector<Keypoint>(found.begin(), found.end())));
}

// Both blurs of a frame, every pixel as float (the 8-bit one's values
// widened), and the float blur split into bands.
std::vector<float> blurred(ImageView image, int bands, float u8_sigma = 1.3f,
                           float float_sigma = 2.45f) {
  Plane<std::uint8_t> u8;
  Plane<float> f, g, scratch;
  gaussian_blur(image, u8_sigma, u8, scratch);
  f.resize(image.width, image.height);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) f.row(y)[x] = static_cast<float>(image.row(y)[x]);
  g.resize(image.width, image.height);
  for (int b = 0; b < bands; ++b)
    gaussian_blur_rows(f, float_sigma, g, image.height * b / bands, image.height * (b + 1) / bands,
                       scratch);
  std::vector<float> out;
  for (int y = 0; y < image.height; ++y) {
    out.insert(out.end(), g.row(y), g.row(y) + image.width);
    for (int x = 0; x < image.width; ++x) out.push_back(u8.row(y)[x]);
  }
  return out;
}

TEST(KeypointBands, BlurInBandsEqualsOneBand) {
  for (const ImageView image : frames().views())
    EXPECT_EQ(blurred(image, 1), blurred(image, 3)) << image.width << "x" << image.height;
}

// The vector loops against the portable ones, where the build has vector
// loops for these kernels: AVX2 on x86-64 (chosen at run time: a CPU without
// it is hardware this test needs), NEON on AArch64 (always there). armhf
// runs the portable loops at every level: nothing to compare.
#if defined(__x86_64__) || defined(__aarch64__)

bool cpu_lacks_vector_loops() {
#if defined(__x86_64__)
  return best_simd_level() != SimdLevel::kAvx2;
#else
  return false;
#endif
}

TEST(KeypointSimd, VectorLoopsEqualPortableLoops) {
  if (cpu_lacks_vector_loops()) GTEST_SKIP() << "needs a CPU with AVX2 (the x86-64 vector loops)";
  std::printf("best level: %s\n", simd_level_name(best_simd_level()));
  for (const ImageView image : frames().views()) {
    std::vector<float> vector_blur, portable_blur;
    std::vector<Keypoint> vector_keypoints, portable_keypoints;
    {
      const test::SimdScope best(best_simd_level());
      vector_blur = blurred(image, 1);
      detect_on(image, 2, 24000, vector_keypoints);
    }
    {
      const test::SimdScope scalar(SimdLevel::kScalar);
      portable_blur = blurred(image, 1);
      detect_on(image, 1, 24000, portable_keypoints);
    }
    ASSERT_EQ(vector_blur.size(), portable_blur.size());
    EXPECT_EQ(
        std::memcmp(vector_blur.data(), portable_blur.data(), vector_blur.size() * sizeof(float)),
        0)
        << image.width << "x" << image.height;
    EXPECT_GT(portable_keypoints.size(), 100u);
    EXPECT_TRUE(same_bytes(vector_keypoints, portable_keypoints))
        << image.width << "x" << image.height << ": " << vector_keypoints.size() << " against "
        << portable_keypoints.size();
  }
}

// The blurs of every radius with a vector copy of its own (1 to 10) and two
// beyond (any radius), on the frames and on crops narrower than a vector
// and than two, where the tails do all or half of a row.
TEST(KeypointSimd, VectorBlurEqualsPortableAtEveryRadius) {
  if (cpu_lacks_vector_loops()) GTEST_SKIP() << "needs a CPU with AVX2 (the x86-64 vector loops)";
  const ImageView scene = frames().scene.view();
  std::vector<ImageView> images = frames().views();
  images.emplace_back(scene.row(100) + 201, 5, 60, scene.stride);
  images.emplace_back(scene.row(40) + 17, 13, 90, scene.stride);
  for (const float sigma :
       {0.3f, 0.6f, 0.95f, 1.2f, 1.6f, 1.95f, 2.3f, 2.6f, 2.95f, 3.3f, 3.6f, 5.f}) {
    for (const ImageView image : images) {
      std::vector<float> vector_blur, portable_blur;
      {
        const test::SimdScope best(best_simd_level());
        vector_blur = blurred(image, 1, sigma, sigma);
      }
      {
        const test::SimdScope scalar(SimdLevel::kScalar);
        portable_blur = blurred(image, 1, sigma, sigma);
      }
      ASSERT_EQ(vector_blur.size(), portable_blur.size());
      EXPECT_EQ(
          std::memcmp(vector_blur.data(), portable_blur.data(), vector_blur.size() * sizeof(float)),
          0)
          << "sigma " << sigma << " (radius " << blur_radius(sigma) << "), " << image.width << "x"
          << image.height;
    }
  }
}

// Triangles of box.png (the appearance, also at half size) against
// triangles of box_in_scene, drawn at random: most are not the same
// texture, which does not matter here; the correlation must be the same.
std::vector<TrianglePatch> correlations(const std::vector<ModelAppearance>& looks,
                                        ImageView frame) {
  std::mt19937 draw(11);
  const auto uniform = [&draw](float lo, float hi) {
    return std::uniform_real_distribution<float>(lo, hi)(draw);
  };
  std::vector<TrianglePatch> out;
  for (int t = 0; t < 3000; ++t) {
    Point2f model[3], scene[3];
    const float size = uniform(6.f, 40.f);
    const float zoom = std::exp(uniform(-1.4f, 1.4f));  // frame / model pixels
    const Point2f m0{uniform(0.f, 320.f), uniform(0.f, 220.f)};
    const Point2f s0{uniform(-20.f, 520.f), uniform(-20.f, 400.f)};
    for (int i = 0; i < 3; ++i) {
      const Point2f d{uniform(-size, size), uniform(-size, size)};
      model[i] = {m0.x + d.x, m0.y + d.y};
      scene[i] = {s0.x + zoom * (d.x + uniform(-3.f, 3.f)),
                  s0.y + zoom * (d.y + uniform(-3.f, 3.f))};
    }
    out.push_back(triangle_patch_correlation(looks[static_cast<std::size_t>(t) % looks.size()],
                                             frame, model, scene));
  }
  return out;
}

TEST(TrianglePatchSimd, VectorSamplingEqualsPortable) {
  if (cpu_lacks_vector_loops()) GTEST_SKIP() << "needs a CPU with AVX2 (the x86-64 vector loops)";
  const platform::GrayImage& box = frames().box;
  ModelAppearance full{box.pixels.data(), box.width, box.height, 1.f};
  // The half-size appearance: every other pixel is enough here.
  std::vector<std::uint8_t> half_pixels;
  const int hw = box.width / 2, hh = box.height / 2;
  for (int y = 0; y < hh; ++y)
    for (int x = 0; x < hw; ++x)
      half_pixels.push_back(box.pixels[static_cast<std::size_t>(2 * y * box.width + 2 * x)]);
  ModelAppearance half{half_pixels.data(), hw, hh, 0.5f};
  const std::vector<ModelAppearance> looks{full, half};
  std::vector<TrianglePatch> vector_patches, portable_patches;
  {
    const test::SimdScope best(best_simd_level());
    vector_patches = correlations(looks, frames().scene.view());
  }
  {
    const test::SimdScope scalar(SimdLevel::kScalar);
    portable_patches = correlations(looks, frames().scene.view());
  }
  ASSERT_EQ(vector_patches.size(), portable_patches.size());
  int measured = 0, mismatches = 0;
  for (std::size_t i = 0; i < portable_patches.size(); ++i) {
    measured += portable_patches[i].measured ? 1 : 0;
    if (vector_patches[i].measured != portable_patches[i].measured ||
        std::memcmp(&vector_patches[i].correlation, &portable_patches[i].correlation,
                    sizeof(float)) != 0)
      ++mismatches;
  }
  std::printf("%d of %zu triangle pairs measured\n", measured, portable_patches.size());
  EXPECT_GT(measured, 1000);
  EXPECT_EQ(mismatches, 0);
}

// The appearance alignment's vector loops (the frame sampling, 4 pixels at
// a time; the normal equations' sums) against the portable ones: box.pgm
// at half size (2x2 means) aligned onto box_in_scene.pgm from its pose
// (tests/data/frames-corners.txt) with the corners moved a few pixels; at
// a third of its size (one sample a level pixel); and moved so that about
// a fifth of it lies left of the frame (pixels whose samples leave the
// frame part of the way through). The same fit, bit for bit.
TEST(AppearanceAlignSimd, VectorLoopsEqualPortable) {
  if (cpu_lacks_vector_loops()) GTEST_SKIP() << "needs a CPU with AVX2 (the x86-64 vector loops)";
  const platform::GrayImage& box = frames().box;
  const int hw = box.width / 2, hh = box.height / 2;
  std::vector<std::uint8_t> half(static_cast<std::size_t>(hw * hh));
  for (int y = 0; y < hh; ++y)
    for (int x = 0; x < hw; ++x) {
      const auto at = [&](int dx, int dy) {
        return static_cast<int>(
            box.pixels[static_cast<std::size_t>((2 * y + dy) * box.width + 2 * x + dx)]);
      };
      half[static_cast<std::size_t>(y * hw + x)] =
          static_cast<std::uint8_t>((at(0, 0) + at(1, 0) + at(0, 1) + at(1, 1) + 2) / 4);
    }
  const AppearanceImage appearance{half.data(), hw, hh,
                                   static_cast<float>(hw) / static_cast<float>(box.width),
                                   static_cast<float>(hh) / static_cast<float>(box.height)};
  const float w = static_cast<float>(box.width - 1), h = static_cast<float>(box.height - 1);
  const Point2f model[4] = {{0.f, 0.f}, {w, 0.f}, {w, h}, {0.f, h}};
  // box_in_scene's corners, each moved by a few pixels.
  const Point2f found[4] = {{117.85f + 3.f, 160.99f - 2.f},
                            {284.55f - 2.f, 174.79f + 3.f},
                            {268.40f + 2.5f, 297.65f + 1.5f},
                            {89.14f - 1.f, 272.24f - 2.5f}};
  std::vector<std::vector<Point2f>> poses(3);
  for (int c = 0; c < 4; ++c) {
    poses[0].push_back(found[c]);
    poses[1].push_back({100.f + (found[c].x - 100.f) / 3.f, 160.f + (found[c].y - 160.f) / 3.f});
    poses[2].push_back({found[c].x - 150.f, found[c].y});
  }
  const ImageView scene = frames().scene.view();
  AppearanceAligner aligner;
  aligner.reserve(hw * hh);
  int measured = 0, aligned = 0, pose = 0;
  for (const std::vector<Point2f>& corners : poses) {
    Homography start{};
    ASSERT_TRUE(fit_homography(model, corners.data(), 4, start));
    Homography vector_h = start, portable_h = start;
    AppearanceFit vector_fit, portable_fit;
    {
      const test::SimdScope best(best_simd_level());
      vector_fit = aligner.align(appearance, scene, vector_h);
    }
    {
      const test::SimdScope scalar(SimdLevel::kScalar);
      portable_fit = aligner.align(appearance, scene, portable_h);
    }
    EXPECT_EQ(vector_fit.measured, portable_fit.measured);
    EXPECT_EQ(vector_fit.aligned, portable_fit.aligned);
    EXPECT_EQ(0, std::memcmp(vector_h.data(), portable_h.data(), sizeof(Homography)));
    EXPECT_EQ(0, std::memcmp(&vector_fit.ncc, &portable_fit.ncc, sizeof(double)));
    EXPECT_EQ(0, std::memcmp(&vector_fit.ncc_before, &portable_fit.ncc_before, sizeof(double)));
    EXPECT_EQ(vector_fit.iterations, portable_fit.iterations);
    std::printf("pose %d: measured %d aligned %d ncc %.4f -> %.4f, %d iterations\n", ++pose,
                portable_fit.measured, portable_fit.aligned, portable_fit.ncc_before,
                portable_fit.ncc, portable_fit.iterations);
    measured += portable_fit.measured ? 1 : 0;
    aligned += portable_fit.aligned ? 1 : 0;
  }
  EXPECT_EQ(measured, 3);
  EXPECT_GE(aligned, 1);
}

#endif  // x86-64 or AArch64

}  // namespace
}  // namespace kg
