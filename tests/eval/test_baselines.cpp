// The OpenCV baselines with several models at once, on opencv-doc images
// with known poses: the graf1 crop in graf3 (ground truth H1to3p.xml) and
// box.png in box_in_scene.png.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "eval/baselines.h"
#include "support/test_data.h"

namespace kg {
namespace {

constexpr int kCropX = 200, kCropY = 150, kCropSize = 300;

Homography graf_truth() {
  cv::FileStorage fs(test::opencv_data("H1to3p.xml"), cv::FileStorage::READ);
  cv::Mat h;
  fs["H13"] >> h;
  h.convertTo(h, CV_64F);
  const cv::Mat g = h * (cv::Mat_<double>(3, 3) << 1, 0, kCropX, 0, 1, kCropY, 0, 0, 1);
  Homography out;
  for (int i = 0; i < 9; ++i) out[static_cast<std::size_t>(i)] = g.at<double>(i / 3, i % 3);
  return out;
}

struct Images {
  cv::Mat graf_crop, box, graf3, box_in_scene;
};

Images load() {
  Images im;
  const cv::Mat graf1 = test::load_gray(test::opencv_data("graf1.png"));
  if (!graf1.empty()) im.graf_crop = graf1(cv::Rect(kCropX, kCropY, kCropSize, kCropSize)).clone();
  im.box = test::load_gray(test::opencv_data("box.png"));
  im.graf3 = test::load_gray(test::opencv_data("graf3.png"));
  im.box_in_scene = test::load_gray(test::opencv_data("box_in_scene.png"));
  return im;
}

TEST(Baselines, EachModelOfAnIndexIsMatchedAndLocated) {
  const Images im = load();
  ASSERT_FALSE(im.graf_crop.empty() || im.box.empty() || im.graf3.empty() ||
               im.box_in_scene.empty());
  cv::setNumThreads(1);
  BaselineOptions options;
  ASSERT_TRUE(parse_baseline("sift-magsac", options));
  BaselineDetector detector(options);
  // The two models, with an empty image among them (never found).
  detector.set_models({im.graf_crop, cv::Mat(), im.box});
  ASSERT_EQ(detector.model_count(), 3);
  EXPECT_GT(detector.model_keypoints(0), 100);
  EXPECT_EQ(detector.model_keypoints(1), 0);

  std::vector<BaselineDetection> found;
  detector.detect(im.graf3, found);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].model_id, 0);
  EXPECT_GE(found[0].inliers, options.min_inliers);
  EXPECT_LE(found[0].inliers, found[0].matches);
  const Homography truth = graf_truth();
  const Point2f outline[4] = {
      {0, 0}, {kCropSize - 1, 0}, {kCropSize - 1, kCropSize - 1}, {0, kCropSize - 1}};
  for (int c = 0; c < 4; ++c) {
    const Point2f g = kg::apply(truth, outline[c]);
    EXPECT_LT(std::hypot(g.x - found[0].corners[c].x, g.y - found[0].corners[c].y), 3.0) << c;
  }
  EXPECT_GE(detector.stats().homographies, 1);
  EXPECT_LE(detector.stats().homographies, 2);
  EXPECT_GT(detector.stats().scene_keypoints, 1000);

  // The box is found; so is, wrongly, the graf crop (15 of its 35 matches
  // fit some homography): the baselines have no pose verification.
  detector.detect(im.box_in_scene, found);
  ASSERT_FALSE(found.empty());
  ASSERT_EQ(found.back().model_id, 2);
  const BaselineDetection sift_box = found.back();
  BaselineOptions akaze;
  ASSERT_TRUE(parse_baseline("akaze-magsac", akaze));
  BaselineDetector other(akaze);
  other.set_models({im.graf_crop, cv::Mat(), im.box});
  other.detect(im.box_in_scene, found);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].model_id, 2);
  for (int c = 0; c < 4; ++c) {
    EXPECT_LT(std::hypot(sift_box.corners[c].x - found[0].corners[c].x,
                         sift_box.corners[c].y - found[0].corners[c].y),
              5.0)
        << c;
  }
}

TEST(Baselines, SingleModelCallAgreesWithTheListCall) {
  const Images im = load();
  ASSERT_FALSE(im.box.empty() || im.box_in_scene.empty());
  cv::setNumThreads(1);
  for (const std::string& name : baseline_names()) {
    BaselineOptions options;
    ASSERT_TRUE(parse_baseline(name, options)) << name;
    EXPECT_EQ(baseline_name(options), name);
    BaselineDetector detector(options);
    detector.set_model(im.box);
    std::vector<BaselineDetection> list;
    detector.detect(im.box_in_scene, list);
    bool found = false;
    Homography h{};
    int inliers = 0;
    detector.detect(im.box_in_scene, found, h, inliers);
    ASSERT_EQ(found, !list.empty()) << name;
    if (found) {
      EXPECT_EQ(inliers, list[0].inliers) << name;
    }
  }
  BaselineOptions unknown;
  EXPECT_FALSE(parse_baseline("surf-ransac", unknown));
  EXPECT_FALSE(parse_baseline("sift", unknown));
}

}  // namespace
}  // namespace kg
