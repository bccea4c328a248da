// RansacParams::min_triangle_correlation on a real pair: box.png found in
// box_in_scene.png with the check on, at the SIFT reference pose; the
// correspondences it keeps correlate, the ones that lie on the box at the
// right place correlate high, and a planted wrong correspondence (a right
// model triangle paired with a frame triangle elsewhere) is rejected.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/index/index_format.h"
#include "core/pose/homography.h"
#include "core/selection/triangle_patch.h"
#include "support/opencv_scenes.h"
#include "support/test_data.h"

namespace kg {
namespace {

constexpr float kThreshold = 0.3f;

TEST(TriangleCheckParam, RangeAndOlderFiles) {
  Params p;
  EXPECT_EQ(p.ransac.min_triangle_correlation, 0.6f)
      << "0.6 by default with the tilted views: re-measure before changing";
  for (const float bad : {-0.1f, 1.f, 2.f}) {
    p.ransac.min_triangle_correlation = bad;
    const Status s = format::validate_params(p);
    EXPECT_FALSE(s) << bad;
    EXPECT_NE(s.message().find("min_triangle_correlation"), std::string::npos) << s.message();
  }
  p.ransac.min_triangle_correlation = 0.45f;
  std::uint8_t block[format::kParamsSize];
  format::serialize_params(p, block);
  Params read;
  ASSERT_TRUE(format::parse_params(block, sizeof block, read));
  EXPECT_EQ(read.ransac.min_triangle_correlation, 0.45f);
}

TEST(TriangleCheck, KeepsTheBoxAndRejectsAPlantedWrongCorrespondence) {
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  const cv::Mat scene = test::load_gray(test::opencv_data("box_in_scene.png"));
  ASSERT_FALSE(box.empty());
  ASSERT_FALSE(scene.empty());
  const Homography truth = test::sift_reference(box, scene);
  Params params;
  test::InMemoryIndex off, on;
  ASSERT_TRUE(test::build_in_memory({{"box", box}}, params, off));
  params.ransac.min_triangle_correlation = kThreshold;
  ASSERT_TRUE(test::build_in_memory({{"box", box}}, params, on));
  ASSERT_FALSE(on.index.appearance(0).empty());

  Detector plain(off.index), checked(on.index);
  DetectionList found_off, found_on;
  ASSERT_TRUE(plain.detect(test::view(scene), found_off).is_ok());
  ASSERT_TRUE(checked.detect(test::view(scene), found_on).is_ok());
  ASSERT_EQ(found_on.size(), 1u);
  const double err = test::max_corner_error(found_on[0], truth, on.index.model(0));
  EXPECT_LT(err, 3.0);
  const int selected = plain.stats().correspondences;
  const int rejected = checked.stats().patch_rejections;
  EXPECT_GT(rejected, 0);
  EXPECT_EQ(static_cast<int>(checked.last_matches().size()), selected - rejected);
  std::printf("box_in_scene: %d of %d correspondences rejected, %d -> %d inliers, %.2f px\n",
              rejected, selected, found_off.empty() ? 0 : found_off[0].inliers, found_on[0].inliers,
              err);

  // The kept correspondences: measured ones correlate at least the
  // threshold, and those at the true pose mostly correlate high.
  const Point2f* model_points = on.index.keypoints();
  const ConstSpan<Keypoint> keypoints = checked.last_keypoints();
  const auto at_true_pose = [&](const KeygraphMatch& m) {
    for (int v = 0; v < 3; ++v) {
      const Point2f p = apply(truth, model_points[m.model_vertices[v]]);
      const Keypoint& k = keypoints[static_cast<std::size_t>(m.scene_vertices[v])];
      if (!(std::hypot(p.x - k.x, p.y - k.y) < 3.0)) return false;
    }
    return true;
  };
  // The same sampled keypoints with the check off (the scene side before
  // the check is the same): the check keeps every right correspondence and
  // drops mostly wrong ones.
  int right_before = 0;
  for (const KeygraphMatch& m : plain.last_matches()) right_before += at_true_pose(m) ? 1 : 0;
  const ModelAppearance look = on.index.appearance(0);
  int right = 0, right_high = 0, measured = 0, wrong_kept_measured = 0;
  const KeygraphMatch* planted_from = nullptr;
  for (const KeygraphMatch& m : checked.last_matches()) {
    if (m.patch_correlation != 0.f) {
      EXPECT_GE(m.patch_correlation, kThreshold);
    }
    const bool at_truth = at_true_pose(m);
    measured += m.patch_correlation != 0.f ? 1 : 0;
    if (!at_truth) {
      wrong_kept_measured += m.patch_correlation != 0.f ? 1 : 0;
      continue;
    }
    ++right;
    right_high += m.patch_correlation > 0.6f ? 1 : 0;
    if (planted_from == nullptr && m.patch_correlation > 0.6f) planted_from = &m;
  }
  std::printf(
      "kept: %zu, measured %d; at the true pose %d (%d above 0.6); elsewhere, measured %d\n",
      checked.last_matches().size(), measured, right, right_high, wrong_kept_measured);
  ASSERT_GT(right, 10);
  EXPECT_GE(right, right_before - 1) << "the check drops right correspondences";
  EXPECT_GT(right_high, right / 2);
  ASSERT_NE(planted_from, nullptr);

  // Planted: the same model triangle with the scene triangle moved to the
  // keypoints nearest where a far part of the box maps (a shifted copy).
  const ImageView frame = test::view(scene);
  Point2f model[3], shifted[3];
  for (int v = 0; v < 3; ++v) {
    model[v] = model_points[planted_from->model_vertices[v]];
    const Keypoint& k = keypoints[static_cast<std::size_t>(planted_from->scene_vertices[v])];
    shifted[v] = {k.x, k.y};
  }
  int wrong_measured = 0, wrong_rejected = 0;
  for (const float dx : {-60.f, -35.f, 35.f, 60.f}) {
    for (const float dy : {-45.f, 45.f}) {
      Point2f moved[3];
      for (int v = 0; v < 3; ++v) moved[v] = {shifted[v].x + dx, shifted[v].y + dy};
      const TrianglePatch wrong = triangle_patch_correlation(look, frame, model, moved);
      if (!wrong.measured) continue;
      ++wrong_measured;
      wrong_rejected += wrong.correlation < kThreshold ? 1 : 0;
    }
  }
  ASSERT_GE(wrong_measured, 6);
  EXPECT_GE(wrong_rejected, wrong_measured - 1);
  const TrianglePatch kept = triangle_patch_correlation(look, frame, model, shifted);
  ASSERT_TRUE(kept.measured);
  EXPECT_GT(kept.correlation, kThreshold);
}

}  // namespace
}  // namespace kg
