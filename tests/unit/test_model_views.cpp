// Simulated model views (build/model_views.h): which views a ViewParams
// asks for, that each view's affine map puts model pixels where the
// rendered view shows them, and that a model built through views finds a
// sign far smaller than its image, which the single-image model cannot.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "build/desktop_detect.h"
#include "build/eval_index.h"
#include "build/model_builder.h"
#include "build/model_views.h"
#include "test_data.h"

namespace kg {
namespace {

cv::Point2d map(const cv::Matx23d& a, cv::Point2d p) {
  return {a(0, 0) * p.x + a(0, 1) * p.y + a(0, 2), a(1, 0) * p.x + a(1, 1) * p.y + a(1, 2)};
}

TEST(ModelViews, FrontalPyramidStopsAtTheSmallestSize) {
  ViewParams params;
  params.max_tilt = 0.f;  // the frontal pyramid alone
  params.min_size = 40.f;
  params.scale_step = 0.5f;
  const std::vector<ModelView> views = model_views(320, 160, params, 3);
  // 320, 160, 80, 40: the last is the first at or under 40 px.
  ASSERT_EQ(views.size(), 4u);
  for (std::size_t i = 0; i < views.size(); ++i) {
    EXPECT_DOUBLE_EQ(views[i].scale, std::pow(0.5, static_cast<double>(i)));
    EXPECT_DOUBLE_EQ(views[i].tilt, 1.0);
    EXPECT_EQ(views[i].size.width, 320 >> i);
    EXPECT_EQ(views[i].size.height, 160 >> i);
  }
}

TEST(ModelViews, WithoutViewsTheLegacyScales) {
  ViewParams off;
  off.min_size = 0.f;
  const std::vector<ModelView> views = model_views(200, 100, off, 3);
  ASSERT_EQ(views.size(), 3u);
  EXPECT_NEAR(views[2].scale, 0.5, 1e-12);
  EXPECT_EQ(views[2].size, cv::Size(100, 50));
}

// keygraph build --max-tilt: ASIFT's spacing of t, whatever the angle.
TEST(ModelViews, TiltLevelsInAsiftSteps) {
  EXPECT_EQ(asift_tilt_levels(30.f), 1);  // t = 1.15
  EXPECT_EQ(asift_tilt_levels(45.f), 1);  // 1.41
  EXPECT_EQ(asift_tilt_levels(60.f), 2);  // 2
  EXPECT_EQ(asift_tilt_levels(70.f), 4);  // 2.92
  EXPECT_EQ(asift_tilt_levels(80.f), 8);  // 5.76: the most validation accepts
  EXPECT_EQ(asift_tilt_levels(0.f), 1);
  EXPECT_EQ(asift_tilt_levels(90.f), 1);  // not a tilt (validation refuses it)
}

TEST(ModelViews, TiltsAtAsiftLongitudes) {
  ViewParams params;
  params.min_size = 1000.f;  // one scale per tilt and longitude
  params.max_tilt = 60.f;    // t = 2
  params.tilt_levels = 2;    // t = 1.5, then 2
  const std::vector<ModelView> views = model_views(200, 200, params, 1);
  // Frontal, then 180 / (72 / 1.5) = 3 longitudes at t = 1.5, 5 at t = 2.
  ASSERT_EQ(views.size(), 1u + 3u + 5u);
  EXPECT_DOUBLE_EQ(views[1].tilt, 1.5);
  EXPECT_DOUBLE_EQ(views[8].tilt, 2.0);
  EXPECT_DOUBLE_EQ(views[5].longitude, 36.0);
  for (const ModelView& v : views) {
    // The map's area scale is scale^2 / tilt.
    const cv::Matx23d& a = v.to_view;
    EXPECT_NEAR(a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0), v.scale * v.scale / v.tilt, 1e-12);
    // The model's outline lands inside the view, touching each side.
    double lo_x = 1e9, lo_y = 1e9, hi_x = -1e9, hi_y = -1e9;
    for (const cv::Point2d c : {cv::Point2d(-0.5, -0.5), cv::Point2d(199.5, -0.5),
                                cv::Point2d(199.5, 199.5), cv::Point2d(-0.5, 199.5)}) {
      const cv::Point2d q = map(a, c);
      lo_x = std::min(lo_x, q.x), lo_y = std::min(lo_y, q.y);
      hi_x = std::max(hi_x, q.x), hi_y = std::max(hi_y, q.y);
    }
    EXPECT_NEAR(lo_x, -0.5, 1e-9);
    EXPECT_NEAR(lo_y, -0.5, 1e-9);
    EXPECT_LE(hi_x, v.size.width - 0.5 + 1e-9);
    EXPECT_LE(hi_y, v.size.height - 0.5 + 1e-9);
    EXPECT_GT(hi_x, v.size.width - 1.5);
    EXPECT_GT(hi_y, v.size.height - 1.5);
  }
}

// A bright square's centre lands where the view's map sends it, in every
// view (tilted, rotated, shrunk), within a fraction of a pixel.
TEST(ModelViews, RenderedViewShowsModelPixelsWhereTheMapSays) {
  cv::Mat model(240, 300, CV_8UC1, cv::Scalar(40));
  const cv::Rect square(180, 60, 24, 24);
  model(square).setTo(220);
  const cv::Point2d centre(square.x + 11.5, square.y + 11.5);
  ViewParams params;
  params.min_size = 90.f;
  params.scale_step = 0.6f;
  params.max_tilt = 60.f;
  params.tilt_levels = 2;
  const std::vector<ModelView> views = model_views(model.cols, model.rows, params, 1);
  ASSERT_GT(views.size(), 20u);
  for (const ModelView& v : views) {
    SCOPED_TRACE("scale " + std::to_string(v.scale) + " tilt " + std::to_string(v.tilt) +
                 " longitude " + std::to_string(v.longitude));
    cv::Mat image, inside;
    render_view(model, v, image, inside);
    ASSERT_EQ(image.size(), v.size);
    ASSERT_EQ(inside.size(), v.size);
    // Intensity above the background, weighted (the square is a few
    // blurred pixels in the smallest views).
    cv::Mat above;
    cv::subtract(image, cv::Scalar(40), above);
    const cv::Moments m = cv::moments(above, false);
    ASSERT_GT(m.m00, 0.0);
    const cv::Point2d want = map(v.to_view, centre);
    EXPECT_NEAR(m.m10 / m.m00, want.x, 0.75);
    EXPECT_NEAR(m.m01 / m.m00, want.y, 0.75);
    // The mask covers the model's image and nothing far outside it.
    const double area = static_cast<double>(model.total()) * v.scale * v.scale / v.tilt;
    EXPECT_NEAR(cv::countNonZero(inside), area, 0.05 * area + 4.0 * (v.size.width + v.size.height));
  }
}

// Rendering never writes into the model image (a blur in place once made
// each view blur the next one's source).
TEST(ModelViews, RenderingLeavesTheModelImageAlone) {
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  ASSERT_FALSE(box.empty());
  const cv::Mat original = box.clone();
  ViewParams params;
  params.min_size = 40.f;
  params.max_tilt = 45.f;
  params.tilt_levels = 1;
  for (const ModelView& v : model_views(box.cols, box.rows, params, 1)) {
    cv::Mat image, inside;
    render_view(box, v, image, inside);
    ASSERT_EQ(cv::norm(box, original, cv::NORM_INF), 0.0) << "view at scale " << v.scale;
  }
}

// box.png shrunk to a quarter (81 px wide) on a textured background: the
// model built through views down to 60 px finds it within a few pixels;
// the paper's single model image (keypoints from 3 scales, arcs at full
// size) does not.
TEST(ModelViews, SmallInstanceFoundOnlyWithViews) {
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  const cv::Mat background = test::load_gray(test::opencv_data("fruits.jpg"));
  ASSERT_FALSE(box.empty());
  ASSERT_FALSE(background.empty());
  cv::Mat scene;
  cv::resize(background, scene, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
  const double scale = 0.25;
  const cv::Point2d at(300.0, 200.0);
  const cv::Matx23d place(scale, 0.0, at.x + 0.5 * scale - 0.5, 0.0, scale,
                          at.y + 0.5 * scale - 0.5);
  cv::Mat blurred;
  cv::GaussianBlur(box, blurred, cv::Size(0, 0), 0.8 * std::sqrt(1.0 / (scale * scale) - 1.0));
  cv::Mat mask(box.size(), CV_8UC1, cv::Scalar(255));
  cv::Mat warped, warped_mask;
  cv::warpAffine(blurred, warped, cv::Mat(place), scene.size(), cv::INTER_LINEAR);
  cv::warpAffine(mask, warped_mask, cv::Mat(place), scene.size(), cv::INTER_NEAREST);
  warped.copyTo(scene, warped_mask);

  auto found = [&](const Params& params, double& corner_error) {
    BuiltModel model;
    EXPECT_TRUE(build_model(box, "box", params, model));
    EvalIndex index;
    EXPECT_TRUE(index.build({model}, params));
    DesktopDetector detector(index.index());
    DetectionList out;
    EXPECT_TRUE(detector.detect(scene, out));
    corner_error = 1e9;
    for (const Detection& d : out) {
      double worst = 0;
      const Point2f outline[4] = {
          {0.f, 0.f},
          {static_cast<float>(box.cols - 1), 0.f},
          {static_cast<float>(box.cols - 1), static_cast<float>(box.rows - 1)},
          {0.f, static_cast<float>(box.rows - 1)}};
      for (int c = 0; c < 4; ++c) {
        const cv::Point2d want = map(place, cv::Point2d(outline[c].x, outline[c].y));
        worst = std::max(worst, std::hypot(d.corners[c].x - want.x, d.corners[c].y - want.y));
      }
      corner_error = std::min(corner_error, worst);
    }
    return !out.empty();
  };
  Params with_views;
  with_views.views.min_size = 60.f;
  double error = 0;
  EXPECT_TRUE(found(with_views, error));
  EXPECT_LT(error, 5.0);
  Params single;
  single.views.min_size = 0.f;
  found(single, error);
  EXPECT_GT(error, 5.0) << "the single-image model now finds the small box: make the test harder";
}

}  // namespace
}  // namespace kg
