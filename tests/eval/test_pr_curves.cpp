// Precision-recall and RANSAC-iteration arithmetic of the evaluation on
// constructed cases whose counts can be checked by hand, and the plots'
// mapping from data to pixels.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <opencv2/core.hpp>

#include "eval/correspondence_pr.h"
#include "eval/plot.h"
#include "eval/pr_curves.h"
#include "eval/truth_report.h"

namespace kg {
namespace {

TEST(PrCurves, CountsSelectedCorrectAndReachedPerThreshold) {
  const std::vector<double> t = {0.1, 0.2, 0.3};
  CurveBuilder b(t, 4);  // four true keypoint correspondences, ids 0..3
  b.add(0.05, true);     // selected from 0.1 on, reaches true 0
  b.reach(0, 0.05);
  b.add(0.15, false);  // a wrong one from 0.2 on
  b.add(0.15, true);   // reaches 1 and 2 from 0.2 on
  b.reach(1, 0.15);
  b.reach(2, 0.15);
  b.add(0.2, true);  // exactly at a threshold: selected there
  b.reach(1, 0.2);   // 1 again: counted once
  b.add(0.5, true);  // beyond the grid: never selected
  b.reach(3, 0.5);
  b.reach(7, 0.1);  // not a true correspondence id: ignored
  const CaseCurve c = b.finish();
  EXPECT_EQ(c.truth, 4);
  EXPECT_EQ(c.selected, (std::vector<long long>{1, 4, 4}));
  EXPECT_EQ(c.correct, (std::vector<long long>{1, 3, 3}));
  EXPECT_EQ(c.recalled, (std::vector<long long>{1, 3, 3}));
  EXPECT_DOUBLE_EQ(case_precision(c, 1), 0.75);
  EXPECT_DOUBLE_EQ(case_recall(c, 0), 0.25);
  EXPECT_TRUE(std::isnan(case_precision(CurveBuilder(t, 2).finish(), 0)));
  EXPECT_TRUE(std::isnan(case_recall(CurveBuilder(t, 0).finish(), 0)));
}

TEST(PrCurves, MeanCurveSkipsUndefinedPoints) {
  const std::vector<double> t = {0.5, 1.0};
  CurveBuilder a(t, 2);  // precision 1 then 0.5, recall 0.5 then 0.5
  a.add(0.4, true);
  a.reach(0, 0.4);
  a.add(0.9, false);
  CurveBuilder none(t, 0);  // no true correspondences: no recall; precision 0 at 1.0
  none.add(0.7, false);
  const CaseCurve ca = a.finish(), cn = none.finish();
  const MeanCurve m = mean_curve(t, {&ca, &cn});
  EXPECT_EQ(m.cases, 2);
  EXPECT_DOUBLE_EQ(m.recall[0], 0.5);
  EXPECT_EQ(m.recall_cases[0], 1);
  EXPECT_DOUBLE_EQ(m.precision[0], 1.0);  // only a selects anything at 0.5
  EXPECT_EQ(m.precision_cases[0], 1);
  EXPECT_DOUBLE_EQ(m.precision[1], 0.25);  // (0.5 + 0) / 2
}

TEST(PrCurves, ExpectedIterationsFollowThePaperFormula) {
  // log(1 - 0.99) / log(1 - 0.5^2) = 16.0078...
  EXPECT_NEAR(expected_iterations(0.5, 2, 0.99), std::log(0.01) / std::log(0.75), 1e-12);
  EXPECT_NEAR(expected_iterations(0.5, 4, 0.99), std::log(0.01) / std::log(1 - 0.0625), 1e-12);
  EXPECT_GT(expected_iterations(0.1, 4, 0.99), 100 * expected_iterations(0.1, 2, 0.99) - 1);
  EXPECT_TRUE(std::isinf(expected_iterations(0.0, 2, 0.99)));
  EXPECT_EQ(expected_iterations(1.0, 4, 0.99), 1.0);
  EXPECT_EQ(threshold_grid(0.0, 0.5, 0.1).size(), 6u);
  EXPECT_NEAR(threshold_grid(0.0, 0.5, 0.1).back(), 0.5, 1e-12);
}

TEST(CorrespondenceTruth, PairsWithinTheToleranceUnderTheHomography) {
  // Model -> scene: x 2x + 10, y 2y + 20.
  const Homography h = {2, 0, 10, 0, 2, 20, 0, 0, 1};
  const std::vector<Point2f> model = {{0, 0}, {10, 10}, {50, 5}};
  const Keypoint scene[] = {{10, 20, 0, 0},      // (0, 0) exactly
                            {31.5f, 40, 0, 0},   // (10, 10) is at (30, 40): 1.5 px
                            {110, 33.5f, 0, 0},  // (50, 5) is at (110, 30): 3.5 px, too far
                            {12, 21, 0, 0}};     // (0, 0) again, 2.2 px
  CorrespondenceTruth truth;
  truth.build(model, scene, 4, h, 3.0);
  EXPECT_EQ(truth.count(), 3);
  EXPECT_GE(truth.id(0, 0), 0);
  EXPECT_GE(truth.id(0, 3), 0);
  EXPECT_GE(truth.id(1, 1), 0);
  EXPECT_EQ(truth.id(2, 2), -1);
  EXPECT_EQ(truth.id(1, 0), -1);
  EXPECT_EQ(truth.id(9, 0), -1);
  EXPECT_NE(truth.id(0, 0), truth.id(0, 3));
}

TEST(KeypointCurves, ThresholdAndRatioSelectionsOnKnownDescriptors) {
  // Unit descriptors in 128-D: model i and scene i are true pairs (identity
  // ground truth); distances set by the angle between them.
  const auto unit = [](double a, int axis) {
    cv::Mat r = cv::Mat::zeros(1, 128, CV_32F);
    r.at<float>(0, axis) = static_cast<float>(std::cos(a));
    r.at<float>(0, axis + 64) = static_cast<float>(std::sin(a));
    return r;
  };
  cv::Mat model, scene;
  model.push_back(unit(0.0, 0));  // m0
  model.push_back(unit(0.0, 1));  // m1
  scene.push_back(unit(0.2, 0));  // s0: |m0 - s0| = 2 sin(0.1) = 0.1997
  scene.push_back(unit(0.6, 1));  // s1: |m1 - s1| = 2 sin(0.3) = 0.591
  scene.push_back(unit(0.0, 2));  // s2: orthogonal to both: sqrt(2)
  const std::vector<Point2f> model_points = {{0, 0}, {100, 0}};
  const Keypoint scene_points[] = {{0, 0, 0, 0}, {100, 0, 0, 0}, {50, 50, 0, 0}};
  CorrespondenceTruth truth;
  truth.build(model_points, scene_points, 3, {1, 0, 0, 0, 1, 0, 0, 0, 1}, 3.0);
  ASSERT_EQ(truth.count(), 2);
  CaseCurve by_distance, by_ratio;
  keypoint_curves(model, scene, truth, {0.3, 0.7, 1.5}, {0.2, 0.5, 1.0}, by_distance, by_ratio);
  // Distance: 0.3 selects (m0, s0); 0.7 adds (m1, s1); 1.5 selects all 6 pairs.
  EXPECT_EQ(by_distance.selected, (std::vector<long long>{1, 2, 6}));
  EXPECT_EQ(by_distance.correct, (std::vector<long long>{1, 2, 2}));
  EXPECT_EQ(by_distance.recalled, (std::vector<long long>{1, 2, 2}));
  // Ratio: m0 0.1997 / 1.414 = 0.141, m1 0.591 / 1.414 = 0.418.
  EXPECT_EQ(by_ratio.selected, (std::vector<long long>{1, 2, 2}));
  EXPECT_EQ(by_ratio.recalled, (std::vector<long long>{1, 2, 2}));
}

TEST(Plot, SeriesAreDrawnWhereTheirDataLies) {
  PlotSpec spec;
  spec.x_label = "recall";
  spec.y_label = "precision";
  PlotSeries s;
  s.label = "test";
  s.x = {0.0, 1.0};
  s.y = {0.25, 0.25};
  s.colour = cv::Scalar(0, 0, 255);
  spec.series = {s};
  spec.legend = LegendCorner::kTopRight;
  const cv::Mat img = render_plot(spec);
  ASSERT_EQ(img.cols, spec.width);
  ASSERT_EQ(img.rows, spec.height);
  const PlotFrame frame(spec);
  const cv::Point2d on = frame.to_pixel(0.5, 0.25), off = frame.to_pixel(0.5, 0.6);
  const cv::Vec3b line = img.at<cv::Vec3b>(cvRound(on.y), cvRound(on.x));
  const cv::Vec3b blank = img.at<cv::Vec3b>(cvRound(off.y), cvRound(off.x));
  EXPECT_GT(line[2], 200);
  EXPECT_LT(line[0], 80);
  EXPECT_GT(blank[0], 200);  // white or light grid, not the series
  // The axes' box is black at its corners.
  const cv::Rect a = frame.area();
  EXPECT_LT(img.at<cv::Vec3b>(a.y + a.height - 1, a.x)[0], 60);
  // Log axis: a decade is the same height everywhere.
  PlotSpec log_spec = spec;
  log_spec.log_y = true;
  log_spec.y_min = 1;
  log_spec.y_max = 1e4;
  const PlotFrame lf(log_spec);
  EXPECT_NEAR(lf.to_pixel(0, 1).y - lf.to_pixel(0, 10).y,
              lf.to_pixel(0, 1000).y - lf.to_pixel(0, 10000).y, 1e-9);
}

// eval --truth's by-size plot (issue 39, item 14): two methods that find
// exactly the same fractions are both visible, and the legend is beside
// the axes, not over the data.
TEST(Plot, SizePlotShowsCoincidentMethodsAndKeepsItsLegendOffTheData) {
  std::vector<TruthRow> rows(2);
  rows[0].method = "keygraph";
  rows[1].method = "sift-magsac";
  for (TruthRow& r : rows) {
    for (const double edge : {40.0, 100.0, 300.0}) {
      TruthBin b;
      b.instances = 4;
      b.found = b.found_iou = 2;
      b.median_size = edge;
      r.by_size.push_back(b);
    }
  }
  const cv::Mat img = truth_size_plot(rows);
  // The axes' box: its vertical edges are the columns that are black for
  // most of the height (the legend's box is short).
  int right_edge = -1;
  for (int x = 0; x < img.cols; ++x) {
    int black = 0;
    for (int y = 0; y < img.rows; ++y)
      black += img.at<cv::Vec3b>(y, x)[0] < 60 && img.at<cv::Vec3b>(y, x)[1] < 60 &&
               img.at<cv::Vec3b>(y, x)[2] < 60;
    if (black > img.rows / 2) right_edge = x;
  }
  ASSERT_GT(right_edge, img.cols / 2);
  int inside[2] = {0, 0}, beside[2] = {0, 0};
  for (int c = 0; c < 2; ++c) {
    const cv::Scalar colour = plot_colour(c);
    for (int y = 0; y < img.rows; ++y) {
      for (int x = 0; x < img.cols; ++x) {
        const cv::Vec3b p = img.at<cv::Vec3b>(y, x);
        const double d =
            std::abs(p[0] - colour[0]) + std::abs(p[1] - colour[1]) + std::abs(p[2] - colour[2]);
        if (d < 30) ++(x < right_edge ? inside[c] : beside[c]);
      }
    }
  }
  EXPECT_GT(inside[0], 300) << "keygraph's lines are hidden";
  EXPECT_GT(inside[1], 300) << "sift-magsac's lines are hidden";
  EXPECT_GT(beside[0], 20) << "keygraph's legend entry is not beside the axes";
  EXPECT_GT(beside[1], 20) << "sift-magsac's legend entry is not beside the axes";
}

// eval --truth's by-size plot when every instance falls in one bin (issue
// 38: a user's 26-frame set drew an empty-looking plot, two lone markers
// and no line): each bin is a step across its width, so the one bin shows.
TEST(Plot, SizePlotDrawsASingleBin) {
  std::vector<TruthRow> rows(1);
  rows[0].method = "keygraph";
  TruthBin b;
  b.lo = 40;
  b.hi = 60;
  b.instances = 26;
  b.found = 13;
  b.found_iou = 13;
  b.median_size = 47;
  rows[0].by_size.push_back(b);
  const cv::Mat img = truth_size_plot(rows);
  const cv::Scalar colour = plot_colour(0);
  // The step's row: y = 0.5 of the axes; count the method's pixels there.
  int drawn = 0, columns = 0;
  for (int x = 0; x < img.cols; ++x) {
    bool any = false;
    for (int y = 0; y < img.rows; ++y) {
      const cv::Vec3b p = img.at<cv::Vec3b>(y, x);
      const double d =
          std::abs(p[0] - colour[0]) + std::abs(p[1] - colour[1]) + std::abs(p[2] - colour[2]);
      if (d < 30) {
        ++drawn;
        any = true;
      }
    }
    columns += any;
  }
  EXPECT_GT(drawn, 300) << "the one bin is not drawn";
  // Wider than the legend's line sample (30 px) and the markers: the step.
  EXPECT_GT(columns, 120);
}

}  // namespace
}  // namespace kg
