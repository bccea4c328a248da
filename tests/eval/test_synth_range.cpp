// The small-sign benchmark (keygraph synth --range, issue 38): one seed
// gives the same scenes at 640x480 and 1280x720 (every sign twice as long
// in the larger frame, at the same distance), its signs reach down to a
// 20 px long edge, and eval bins them by long edge and distance.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "eval/quad_geometry.h"
#include "eval/synth/range_frame.h"
#include "eval/synth/synth_set.h"
#include "eval/synth_eval.h"

namespace kg {
namespace {

SynthSetOptions range_set(int width, int height, int frames) {
  SynthSetOptions o;
  o.backgrounds = KG_OPENCV_DATA_DIR;
  o.seed = 11;
  o.signs = 4;
  o.frames = frames;
  o.sign_free_fraction = 0.1;
  o.range = true;
  o.range_frame = range_frame_options(width, height);
  return o;
}

TEST(SynthRange, TheSameScenesAtTwiceTheResolution) {
  SynthManifest small, large;
  SynthSetImages small_images, large_images;
  ASSERT_TRUE(render_synth_set(range_set(640, 480, 12), small, small_images).is_ok());
  ASSERT_TRUE(render_synth_set(range_set(1280, 720, 12), large, large_images).is_ok());
  EXPECT_EQ(small.width, 640);
  EXPECT_EQ(large.height, 720);
  int signs = 0;
  for (std::size_t f = 0; f < small.frames.size(); ++f) {
    const SynthFrameInfo& a = small.frames[f].info;
    const SynthFrameInfo& b = large.frames[f].info;
    ASSERT_EQ(large_images.frames[f].cols, 1280);
    ASSERT_EQ(large_images.frames[f].rows, 720);
    ASSERT_EQ(a.sign, b.sign) << f;
    EXPECT_EQ(small.frames[f].background, large.frames[f].background);
    if (a.sign < 0) continue;
    ++signs;
    EXPECT_GT(a.distance, 0);
    EXPECT_DOUBLE_EQ(a.distance, b.distance);
    // The 1280x720 frame shows the 640x480 one's rows 60..420 twice as large.
    for (int c = 0; c < 4; ++c) {
      EXPECT_NEAR(b.corners[c].x, 2 * a.corners[c].x + 0.5, 1e-2) << f;
      EXPECT_NEAR(b.corners[c].y, 2 * (a.corners[c].y - 60) + 0.5, 1e-2) << f;
      EXPECT_GE(b.corners[c].y, 0);
      EXPECT_LE(b.corners[c].y, 719);
    }
    // The same pixels, up to noise and blur: the larger frame halved
    // matches the smaller one's band on the sign.
    cv::Mat halved;
    cv::resize(large_images.frames[f], halved, cv::Size(640, 360), 0, 0, cv::INTER_AREA);
    const cv::Mat band = small_images.frames[f](cv::Rect(0, 60, 640, 360));
    cv::Mat diff;
    cv::absdiff(halved, band, diff);
    EXPECT_LT(cv::mean(diff)[0], 12) << f;
    cv::Mat other;
    cv::absdiff(halved,
                small_images.frames[(f + 1) % small.frames.size()](cv::Rect(0, 60, 640, 360)),
                other);
    EXPECT_GT(cv::mean(other)[0], cv::mean(diff)[0] + 10) << f;
  }
  EXPECT_GE(signs, 9);
}

TEST(SynthRange, SignsReachDownToTwentyPixels) {
  SynthManifest m;
  SynthSetImages images;
  ASSERT_TRUE(render_synth_set(range_set(640, 480, 60), m, images).is_ok());
  int under40 = 0, under30 = 0, over100 = 0;
  double smallest = 1e9;
  for (const SynthFrameEntry& f : m.frames) {
    if (f.info.sign < 0) continue;
    const double edge = longest_side(f.info.corners);
    smallest = std::min(smallest, edge);
    under40 += edge < 40;
    under30 += edge < 30;
    over100 += edge >= 100;
    // Distance and size: a 30 cm sign at focal 600 px, shortened by its
    // turn (its nearer side a little longer under perspective).
    EXPECT_LE(edge, 1.15 * 600 * kRangeSignMetres / f.info.distance) << f.file;
    EXPECT_GE(edge, 0.5 * 600 * kRangeSignMetres / f.info.distance) << f.file;
  }
  EXPECT_GE(smallest, 10);
  EXPECT_LT(smallest, 25);
  EXPECT_GE(under40, 10);
  EXPECT_GE(under30, 4);
  EXPECT_GE(over100, 5);
  // The manifest keeps the distance.
  SynthManifest parsed;
  ASSERT_TRUE(parse_manifest(manifest_text(m), parsed).is_ok());
  for (std::size_t f = 0; f < m.frames.size(); ++f)
    EXPECT_EQ(parsed.frames[f].info.distance, m.frames[f].info.distance);
  SynthManifest bad;
  EXPECT_FALSE(parse_manifest("keygraph-synth 1\nsign 0 a a.png 10 10\n"
                              "frame f.png sign -1 distance -2\n",
                              bad)
                   .is_ok());
}

TEST(SynthRange, OnlyFramesOfTheSameCamera) {
  EXPECT_TRUE(valid_range_frame_size(640, 480));
  EXPECT_TRUE(valid_range_frame_size(1280, 720));
  EXPECT_TRUE(valid_range_frame_size(1920, 1080));
  EXPECT_FALSE(valid_range_frame_size(640, 640));   // more than the reference shows
  EXPECT_FALSE(valid_range_frame_size(1280, 600));  // less than its 16:9 band
  SynthManifest m;
  SynthSetImages images;
  SynthSetOptions o = range_set(640, 480, 2);
  o.range_frame.height = 100;
  EXPECT_FALSE(render_synth_set(o, m, images).is_ok());
}

TEST(SynthEval, BinsByLongEdgeAndDistance) {
  std::vector<SynthCase> cases;
  const double edges[] = {15, 25, 35, 50, 80, 120, 200, 25};
  const double metres[] = {9.5, 7, 5, 3.6, 2.2, 1.4, 0.8, 7};
  for (int i = 0; i < 8; ++i) {
    SynthCase c;
    c.method = "keygraph";
    c.index_size = 1;
    c.sign = 0;
    c.long_edge = edges[i];
    c.distance = metres[i];
    c.found = i >= 4 && i < 7;
    c.found_iou = i >= 3 && i < 7;
    cases.push_back(c);
  }
  SynthCase sign_free;
  sign_free.method = "keygraph";
  sign_free.index_size = 1;
  cases.push_back(sign_free);
  SynthEvalOptions options;
  options.methods = {"keygraph"};
  const std::vector<SynthScaleRow> by_edge = synth_by_bins(cases, options, SynthBinBy::kLongEdge);
  ASSERT_EQ(by_edge.size(), 1u);
  EXPECT_EQ(by_edge[0].frames, (std::vector<int>{1, 2, 1, 1, 1, 1, 1}));
  EXPECT_EQ(by_edge[0].found, (std::vector<int>{0, 0, 0, 0, 1, 1, 1}));
  EXPECT_EQ(by_edge[0].found_iou, (std::vector<int>{0, 0, 0, 1, 1, 1, 1}));
  const std::vector<SynthScaleRow> by_distance =
      synth_by_bins(cases, options, SynthBinBy::kDistance);
  EXPECT_EQ(by_distance[0].frames, (std::vector<int>{2, 1, 1, 1, 2, 1}));
  const std::string text = synth_bins_text(by_edge, SynthBinBy::kLongEdge);
  EXPECT_NE(text.find("20-30"), std::string::npos) << text;
  EXPECT_NE(text.find("160+"), std::string::npos) << text;
  EXPECT_NE(text.find("1/1 1/1"), std::string::npos) << text;
  // Without distances (the default sets) there is no distance table.
  for (SynthCase& c : cases) c.distance = 0;
  EXPECT_EQ(
      synth_bins_text(synth_by_bins(cases, options, SynthBinBy::kDistance), SynthBinBy::kDistance),
      "");
}

}  // namespace
}  // namespace kg
