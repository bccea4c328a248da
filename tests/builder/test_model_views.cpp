// Simulated model views (builder/model_views.h): which views a ViewParams
// asks for, that each view's affine map puts model pixels where the
// rendered view shows them, and that a model built through views finds a
// sign far smaller than its image, which the single-image model cannot.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "builder/desktop_detect.h"
#include "builder/in_memory_index.h"
#include "builder/model_builder.h"
#include "builder/model_views.h"
#include "support/test_data.h"

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

// views.max_scale: frontal views each 1 / scale_step larger, after all the
// others, which stay as they were.
TEST(ModelViews, LargerViewsComeLastUpToTheLargestScale) {
  ViewParams params;
  params.min_size = 40.f;
  params.max_tilt = 45.f;
  params.tilt_levels = 1;
  const std::vector<ModelView> base = model_views(320, 160, params, 1);
  params.max_scale = 2.f;
  const std::vector<ModelView> views = model_views(320, 160, params, 1);
  ASSERT_EQ(views.size(), base.size() + 2);
  for (std::size_t i = 0; i < base.size(); ++i) {
    EXPECT_EQ(views[i].scale, base[i].scale);
    EXPECT_EQ(views[i].tilt, base[i].tilt);
    EXPECT_EQ(views[i].longitude, base[i].longitude);
    EXPECT_EQ(views[i].size, base[i].size);
  }
  const double step = 1.0 / params.scale_step;
  for (int up = 1; up <= 2; ++up) {
    const ModelView& v = views[base.size() + up - 1];
    EXPECT_DOUBLE_EQ(v.scale, std::pow(step, up));
    EXPECT_EQ(v.tilt, 1.0);
    EXPECT_EQ(v.longitude, 0.0);
    EXPECT_EQ(v.size.width, static_cast<int>(std::ceil(320 * v.scale - 1e-6)));
    EXPECT_NEAR(v.to_view(0, 0), v.scale, 1e-12);
  }
  // Just under one step up: none.
  params.max_scale = 1.4f;
  EXPECT_EQ(model_views(320, 160, params, 1).size(), base.size());
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
  params.max_scale = 2.f;  // and enlarged views, rendered by cubic interpolation
  const std::vector<ModelView> views = model_views(model.cols, model.rows, params, 1);
  ASSERT_GT(views.size(), 20u);
  ASSERT_GT(views.back().scale, 1.5);  // 1 / 0.6
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
    InMemoryIndex index;
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

// The other way: a page of text shown 1.8x larger than its image and turned
// by 20 degrees. Its fine strokes are coarse blobs in the frame that no view
// of the model at its own size or smaller shows; views up to sqrt(2) larger
// (views.max_scale) find it, within a few pixels at every corner.
TEST(ModelViews, LargeInstanceFoundWithLargerViews) {
  const cv::Mat text = test::load_gray(test::opencv_data("imageTextN.png"));
  const cv::Mat background = test::load_gray(test::opencv_data("fruits.jpg"));
  ASSERT_FALSE(text.empty());
  ASSERT_FALSE(background.empty());
  cv::Mat scene;
  cv::resize(background, scene, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
  const cv::Point2d centre(0.5 * text.cols, 0.5 * text.rows);
  cv::Mat place = cv::getRotationMatrix2D(centre, 20.0, 1.8);
  place.at<double>(0, 2) += 320.0 - centre.x;
  place.at<double>(1, 2) += 240.0 - centre.y;
  cv::Mat warped, warped_mask;
  const cv::Mat mask(text.size(), CV_8UC1, cv::Scalar(255));
  cv::warpAffine(text, warped, place, scene.size(), cv::INTER_LINEAR);
  cv::warpAffine(mask, warped_mask, place, scene.size(), cv::INTER_NEAREST);
  warped.copyTo(scene, warped_mask);
  const cv::Matx23d to_scene(place);

  auto detect = [&](float max_scale, DetectionList& out) {
    Params params;
    params.views.max_scale = max_scale;
    BuiltModel model;
    ASSERT_TRUE(build_model(text, "text", params, model));
    InMemoryIndex index;
    ASSERT_TRUE(index.build({model}, params));
    DesktopDetector detector(index.index());
    ASSERT_TRUE(detector.detect(scene, out));
  };
  DetectionList at_own_size, with_larger;
  detect(1.f, at_own_size);
  detect(1.42f, with_larger);
  // Corners only partly inside the frame: the error of the model points
  // the frame shows, on a grid.
  auto worst_error = [&](const Detection& d) {
    double worst = 0.0;
    for (int gy = 0; gy <= 10; ++gy) {
      for (int gx = 0; gx <= 10; ++gx) {
        const Point2f m{static_cast<float>(gx * (text.cols - 1) / 10.0),
                        static_cast<float>(gy * (text.rows - 1) / 10.0)};
        const cv::Point2d want = map(to_scene, cv::Point2d(m.x, m.y));
        if (want.x < 0 || want.y < 0 || want.x > 639 || want.y > 479) continue;
        const Point2f got = kg::apply(d.homography, m);
        worst = std::max(worst, std::hypot(got.x - want.x, got.y - want.y));
      }
    }
    return worst;
  };
  ASSERT_EQ(with_larger.size(), 1u);
  EXPECT_LT(worst_error(with_larger[0]), 3.0);
  for (const Detection& d : at_own_size)
    EXPECT_GT(worst_error(d), 3.0) << "found without the larger views: make the test harder";
}

}  // namespace
}  // namespace kg
