// Keypoint repeatability (eval/repeatability.h): exact counts on keypoint
// grids with known homographies, the detectors on graf1 against a
// synthetic warp of it, and the Oxford-layout evaluation on a small dataset
// written here from warps with known homographies.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "eval/repeatability.h"
#include "eval/repeatability_report.h"
#include "support/test_data.h"

namespace kg {
namespace {

constexpr float kSpacing = 12.f;

// cols x rows keypoints 12 px apart from (6, 6), strongest first in row order.
std::vector<Keypoint> grid(int cols, int rows, float dx = 0.f, float dy = 0.f) {
  std::vector<Keypoint> out;
  for (int j = 0; j < rows; ++j) {
    for (int k = 0; k < cols; ++k) {
      const float response = static_cast<float>(cols * rows - static_cast<int>(out.size()));
      out.push_back({6.f + kSpacing * static_cast<float>(k) + dx,
                     6.f + kSpacing * static_cast<float>(j) + dy, 2.f, response});
    }
  }
  return out;
}

Homography translation(double tx, double ty) {
  return {1, 0, tx, 0, 1, ty, 0, 0, 1};
}

TEST(MeasureRepeatability, CountsOnlyModelKeypointsProjectingInsideTheScene) {
  // Model: 25 x 20 grid (x 6..294, y 6..234) in 300 x 240, moved 100 px
  // right into a scene of the same size: columns 0..16 (x <= 199) land inside.
  const std::vector<Keypoint> model = grid(25, 20);
  // Scene keypoints at the even columns' projections; odd columns' 6 px off.
  std::vector<Keypoint> scene;
  for (const Keypoint& k : model) {
    const int column = static_cast<int>(std::lround((k.x - 6.f) / kSpacing));
    scene.push_back({k.x + 100.f, k.y + (column % 2 == 0 ? 0.f : 6.f), 2.f, k.response});
  }
  const RepeatabilityParams params;
  const PairRepeatability r =
      measure_repeatability(model, {300, 240}, scene, {300, 240}, translation(100, 0), params);
  EXPECT_EQ(r.model_keypoints, 500);
  EXPECT_EQ(r.scene_keypoints, 500);
  EXPECT_EQ(r.model_inside, 17 * 20);
  EXPECT_EQ(r.model_repeated, 9 * 20);  // even columns 0, 2, ..., 16
  // Shifted 15 px both ways, every projection is >= 3 px from each axis of
  // the scene lattice: nothing by chance.
  EXPECT_GT(r.model_inside_shifted, 0);
  EXPECT_EQ(r.model_repeated_shifted, 0);
}

TEST(MeasureRepeatability, ChanceShiftLandsOnTheDiagonalNeighbour) {
  const std::vector<Keypoint> model = grid(25, 20);
  RepeatabilityParams params;
  params.chance_shift = kSpacing;  // onto the next keypoint down and right
  const PairRepeatability r =
      measure_repeatability(model, {300, 240}, model, {300, 240}, translation(0, 0), params);
  EXPECT_EQ(r.model_inside, 500);
  EXPECT_EQ(r.model_repeated, 500);
  // Shifted inside (x + 12 <= 299, y + 12 <= 239): every column and row
  // but the last; each then has its diagonal neighbour.
  EXPECT_EQ(r.model_inside_shifted, 24 * 19);
  EXPECT_EQ(r.model_repeated_shifted, 24 * 19);
}

TEST(MeasureRepeatability, PerspectiveSendingPointsBehindTheCameraCountsThemOutside) {
  // w = 1 - x / 150: x' = x / w and y' = y / w for x < 150, behind the
  // camera (w <= 0) beyond. Inside the 300 x 240 scene: x <= 99.9 and
  // y <= 239 (1 - x / 150), i.e. 19, 18, 16, 14, 13, 11, 10 and 8 grid
  // points in the columns x = 6, 18, ..., 90.
  const std::vector<Keypoint> model = grid(25, 20);
  const Homography h = {1, 0, 0, 0, 1, 0, -1.0 / 150, 0, 1};
  const PairRepeatability r =
      measure_repeatability(model, {300, 240}, model, {300, 240}, h, RepeatabilityParams{});
  EXPECT_EQ(r.model_inside, 19 + 18 + 16 + 14 + 13 + 11 + 10 + 8);
  EXPECT_LE(r.model_repeated, r.model_inside);
  EXPECT_EQ(r.sampled_inside, 500);  // the inverse maps the whole scene into the model
}

TEST(MeasureRepeatability, TrianglesNeedThreeRepeatedVerticesAndModelArcs) {
  const std::vector<Keypoint> model = grid(25, 20);
  RepeatabilityParams params;  // sampling at 10 px keeps every 12 px grid point
  const cv::Size size(300, 240);
  const PairRepeatability same =
      measure_repeatability(model, size, model, size, translation(0, 0), params);
  EXPECT_EQ(same.sampled, 500);
  EXPECT_EQ(same.sampled_inside, 500);
  EXPECT_EQ(same.sampled_repeated, 500);
  // A triangulation of 500 points, 86 of them on the hull: 2n - h - 2.
  EXPECT_EQ(same.triangles, 2 * 500 - 86 - 2);
  EXPECT_EQ(same.triangles_repeated, same.triangles);
  // Every edge is 12 px (Chebyshev) long: model arcs within 10..100.
  EXPECT_EQ(same.triangles_keygraph, same.triangles);

  params.min_arc = 13.f;  // no edge is a model arc any more
  EXPECT_EQ(
      measure_repeatability(model, size, model, size, translation(0, 0), params).triangles_keygraph,
      0);
  params.min_arc = 10.f;

  // Scene 5 px off its true place: no vertex is repeated.
  const std::vector<Keypoint> off = grid(25, 20, 5.f, 0.f);
  const PairRepeatability shifted =
      measure_repeatability(model, size, off, size, translation(0, 0), params);
  EXPECT_EQ(shifted.sampled_repeated, 0);
  EXPECT_GT(shifted.triangles, 800);
  EXPECT_EQ(shifted.triangles_repeated, 0);

  // Only the scene's left half (x < 150) is seen by a 150 px wide model:
  // columns 0..11 (x <= 138) are in view, so 12 x 20 vertices and the
  // 2 * 11 * 19 triangles between them.
  const std::vector<Keypoint> left = grid(12, 20);
  const PairRepeatability half =
      measure_repeatability(left, {150, 240}, model, size, translation(0, 0), params);
  EXPECT_EQ(half.sampled_inside, 12 * 20);
  EXPECT_EQ(half.sampled_repeated, 12 * 20);
  EXPECT_EQ(half.triangles, 2 * 11 * 19);
  EXPECT_EQ(half.triangles_repeated, half.triangles);
}

TEST(MeasureRepeatability, SamplingSkipsKeypointsCloserThanTheSampleDistance) {
  // Each grid point has a weaker twin 4 px right: sampling keeps the stronger.
  std::vector<Keypoint> scene = grid(25, 20);
  for (Keypoint k : grid(25, 20, 4.f, 0.f)) {
    k.response -= 1000.f;
    scene.push_back(k);
  }
  const PairRepeatability r = measure_repeatability(grid(25, 20), {300, 240}, scene, {300, 240},
                                                    translation(0, 0), RepeatabilityParams{});
  EXPECT_EQ(r.scene_keypoints, 1000);
  EXPECT_EQ(r.sampled, 500);
  EXPECT_EQ(r.sampled_repeated, 500);
}

TEST(RepeatabilityDetector, ParsesSettingsForOwnDetectorsOnly) {
  RepeatabilityDetector d;
  ASSERT_TRUE(parse_repeatability_detector("hessian:threshold=0.0002:levels=2", Params{}, d));
  EXPECT_EQ(d.method, RepeatabilityMethod::kHessian);
  EXPECT_FLOAT_EQ(d.params.keypoints.hessian_threshold, 0.0002f);
  EXPECT_EQ(d.params.keypoints.hessian_levels, 2);
  EXPECT_EQ(d.label, "hessian:threshold=0.0002:levels=2");
  ASSERT_TRUE(
      parse_repeatability_detector("mser:delta=8:graph.scene_sample_distance=8", Params{}, d));
  EXPECT_EQ(d.params.keypoints.detector, KeypointDetector::kMser);
  EXPECT_EQ(d.params.keypoints.mser_delta, 8);
  EXPECT_FLOAT_EQ(d.params.graph.scene_sample_distance, 8.f);
  // The base (--set) parameters carry over.
  Params base;
  base.keypoints.hessian_octaves = 3;
  ASSERT_TRUE(parse_repeatability_detector("hessian", base, d));
  EXPECT_EQ(d.params.keypoints.hessian_octaves, 3);

  EXPECT_FALSE(parse_repeatability_detector("harris", Params{}, d));
  EXPECT_FALSE(parse_repeatability_detector("sift:threshold=1", Params{}, d));
  EXPECT_FALSE(parse_repeatability_detector("hessian:levels=0", Params{}, d));
  EXPECT_FALSE(parse_repeatability_detector("hessian:nonsense=1", Params{}, d));
  EXPECT_FALSE(parse_repeatability_detector("hessian:threshold", Params{}, d));
}

// graf1 rotated by 12 degrees, scaled by 0.85, with a little perspective.
Homography synthetic_warp() {
  return {0.85 * std::cos(0.21),
          -0.85 * std::sin(0.21),
          120,
          0.85 * std::sin(0.21),
          0.85 * std::cos(0.21),
          20,
          2e-5,
          1e-5,
          1};
}

cv::Mat warp(const cv::Mat& gray, const Homography& h) {
  cv::Mat out;
  cv::warpPerspective(gray, out, cv::Mat(3, 3, CV_64F, const_cast<double*>(h.data())), gray.size(),
                      cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(128));
  return out;
}

TEST(RepeatabilityKeypoints, EveryDetectorRepeatsOnAKnownWarpOfGraf1) {
  const cv::Mat graf = test::load_gray(test::opencv_data("graf1.png"));
  ASSERT_FALSE(graf.empty());
  const Homography h = synthetic_warp();
  const cv::Mat scene = warp(graf, h);
  for (const char* name : {"hessian", "mser", "sift", "orb", "akaze"}) {
    SCOPED_TRACE(name);
    RepeatabilityDetector d;
    ASSERT_TRUE(parse_repeatability_detector(name, Params{}, d));
    RepeatabilityKeypoints detector(d);
    std::vector<Keypoint> a, b;
    detector.detect(graf, 4000, a);
    detector.detect(scene, 4000, b);
    ASSERT_GT(a.size(), 200u);
    ASSERT_LE(a.size(), 4000u);
    for (std::size_t i = 1; i < a.size(); ++i) ASSERT_GE(a[i - 1].response, a[i].response);
    // The same image: the detectors are deterministic, so all repeat.
    const PairRepeatability self =
        measure_repeatability(a, graf.size(), a, graf.size(), {1, 0, 0, 0, 1, 0, 0, 0, 1}, {});
    EXPECT_EQ(self.model_repeated, self.model_inside);
    EXPECT_EQ(self.triangles_repeated, self.triangles);
    // The warp: well above the chance level, and above it by far more than
    // under a pose 10 px wrong.
    const PairRepeatability r = measure_repeatability(a, graf.size(), b, scene.size(), h, {});
    const Homography wrong = {h[0], h[1], h[2] + 10, h[3], h[4], h[5], h[6], h[7], h[8]};
    const PairRepeatability w = measure_repeatability(a, graf.size(), b, scene.size(), wrong, {});
    const double rep = static_cast<double>(r.model_repeated) / r.model_inside;
    const double chance = static_cast<double>(r.model_repeated_shifted) / r.model_inside_shifted;
    const double rep_wrong = static_cast<double>(w.model_repeated) / w.model_inside;
    EXPECT_GT(r.model_inside, 100);
    EXPECT_GT(rep, 0.55);
    EXPECT_GT(rep, 2 * chance);
    EXPECT_LT(rep_wrong, rep / 2);
    EXPECT_GT(r.triangles_repeated, w.triangles_repeated);
  }
}

TEST(EvaluateRepeatability, RunsTheOxfordLayoutWrittenFromKnownWarps) {
  namespace fs = std::filesystem;
  const cv::Mat graf = test::load_gray(test::opencv_data("graf1.png"));
  ASSERT_FALSE(graf.empty());
  cv::Mat small;
  cv::resize(graf, small, cv::Size(400, 320), 0, 0, cv::INTER_AREA);
  const fs::path root = fs::path(KG_TEST_OUTPUT_DIR) / "repeatability_dataset";
  fs::remove_all(root);
  fs::create_directories(root / "graf");
  ASSERT_TRUE(cv::imwrite((root / "graf" / "img1.png").string(), small));
  for (int n = 2; n <= 6; ++n) {
    // Rotations of 3 degrees per step about the centre, a slight zoom.
    const double a = 0.05 * (n - 1), s = 1.0 - 0.03 * (n - 1);
    const double c = s * std::cos(a), si = s * std::sin(a);
    const Homography h = {c, -si, 200 - c * 200 + si * 160, si, c, 160 - si * 200 - c * 160, 0,
                          0, 1};
    ASSERT_TRUE(cv::imwrite((root / "graf" / ("img" + std::to_string(n) + ".png")).string(),
                            warp(small, h)));
    std::ofstream out(root / "graf" / ("H1to" + std::to_string(n) + "p"));
    out.precision(17);
    for (int i = 0; i < 9; ++i) out << h[static_cast<std::size_t>(i)] << (i % 3 == 2 ? '\n' : ' ');
  }

  RepeatabilityOptions options;
  options.dataset = root.string();
  for (const char* name : {"hessian", "orb"}) {
    RepeatabilityDetector d;
    ASSERT_TRUE(parse_repeatability_detector(name, Params{}, d));
    options.detectors.push_back(d);
  }
  std::vector<RepeatabilityCase> cases;
  std::vector<DetectionTiming> timings;
  ASSERT_TRUE(evaluate_repeatability(options, cases, timings));
  ASSERT_EQ(cases.size(), 10u);  // 2 detectors x img2..img6
  ASSERT_EQ(timings.size(), 12u);
  for (const RepeatabilityCase& c : cases) {
    SCOPED_TRACE(c.detector + " img" + std::to_string(c.degree));
    EXPECT_EQ(c.subset, "graf");
    EXPECT_GT(c.counts.model_inside, 50);
    EXPECT_GT(static_cast<double>(c.counts.model_repeated) / c.counts.model_inside, 0.6);
  }
  const RepeatabilityTally hessian = tally_repeatability(cases, timings, "hessian", "", 0);
  EXPECT_EQ(hessian.pairs, 5);
  EXPECT_EQ(hessian.images, 6);
  EXPECT_EQ(hessian.pixels, 6LL * 400 * 320);
  EXPECT_GT(hessian.repeatability(), 2 * hessian.chance());
  const std::string text = repeatability_text(cases, timings, options);
  EXPECT_NE(text.find("\ngraf\n"), std::string::npos);
  EXPECT_NE(text.find("overall"), std::string::npos);
  const std::string csv = repeatability_csv(cases, timings);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 11);  // header + 10 cases

  // A missing homography and a missing directory are errors.
  fs::remove(root / "graf" / "H1to4p");
  EXPECT_FALSE(evaluate_repeatability(options, cases, timings));
  options.dataset = (root / "absent").string();
  EXPECT_FALSE(evaluate_repeatability(options, cases, timings));
}

}  // namespace
}  // namespace kg
