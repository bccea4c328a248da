// The synthetic sign benchmark: the signs and frames are a function of the
// seed, the ground-truth corners are where the sign's corners were drawn,
// the manifest round-trips, scores are computed as documented, and the
// keygraph detector finds signs in a small generated set.
#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "eval/synth/sign_catalogue.h"
#include "eval/synth/synth_frame.h"
#include "eval/synth/synth_set.h"
#include "eval/synth_eval.h"
#include "keygraph/param_text.h"

namespace kg {
namespace {

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

TEST(SignCatalogue, FiftyDistinctSignsDeterministicForASeed) {
  ASSERT_GE(sign_catalogue_size(), 50);
  std::set<std::string> names;
  int styled_differently = 0;
  for (int i = 0; i < sign_catalogue_size(); ++i) {
    const SignImage a = render_sign(i, 7), b = render_sign(i, 7), c = render_sign(i, 8);
    ASSERT_FALSE(a.image.empty()) << i;
    EXPECT_EQ(a.image.type(), CV_8UC3);
    EXPECT_TRUE(same(a.image, b.image)) << a.name;
    styled_differently += !same(a.image, c.image);
    names.insert(a.name);
    EXPECT_GE(std::min(a.image.cols, a.image.rows), 100) << a.name;
    EXPECT_LE(std::max(a.image.cols, a.image.rows), 800) << a.name;
    // Low texture, but not blank: the sign has drawn content.
    cv::Mat gray;
    cv::cvtColor(a.image, gray, cv::COLOR_BGR2GRAY);
    cv::Scalar mean, dev;
    cv::meanStdDev(gray, mean, dev);
    EXPECT_GT(dev[0], 15.0) << a.name;
  }
  EXPECT_EQ(static_cast<int>(names.size()), sign_catalogue_size());
  EXPECT_EQ(styled_differently, sign_catalogue_size());
  EXPECT_TRUE(render_sign(-1, 1).image.empty());
  EXPECT_TRUE(render_sign(sign_catalogue_size(), 1).image.empty());
}

// A sign whose four corner quadrants have four different colours, on black.
cv::Mat quadrant_sign(int w, int h) {
  cv::Mat s(h, w, CV_8UC3);
  const cv::Scalar colours[4] = {{0, 0, 255}, {0, 255, 0}, {255, 0, 0}, {0, 255, 255}};
  s(cv::Rect(0, 0, w / 2, h / 2)).setTo(colours[0]);
  s(cv::Rect(w / 2, 0, w - w / 2, h / 2)).setTo(colours[1]);
  s(cv::Rect(w / 2, h / 2, w - w / 2, h - h / 2)).setTo(colours[2]);
  s(cv::Rect(0, h / 2, w / 2, h - h / 2)).setTo(colours[3]);
  return s;
}

TEST(SynthFrame, GroundTruthCornersAreWhereTheSignsCornersAreDrawn) {
  const cv::Mat sign = quadrant_sign(300, 180);
  // Corner colour, clockwise from top-left (as sign_outline orders them).
  const cv::Vec3b expected[4] = {{0, 0, 255}, {0, 255, 0}, {255, 0, 0}, {0, 255, 255}};
  SynthFrameOptions options;
  Rng rng(42);
  for (int trial = 0; trial < 25; ++trial) {
    const Homography h = random_sign_pose(sign.size(), options, rng);
    cv::Mat frame(options.height, options.width, CV_8UC3, cv::Scalar(0, 0, 0)), alpha;
    composite_sign(frame, sign, h, alpha);
    Point2f outline[4], corners[4];
    sign_outline(sign.size(), outline);
    double cx = 0, cy = 0;
    for (int c = 0; c < 4; ++c) {
      corners[c] = kg::apply(h, outline[c]);
      ASSERT_GE(corners[c].x, options.margin - 1e-3);
      ASSERT_LE(corners[c].x, options.width - 1 - options.margin + 1e-3);
      ASSERT_GE(corners[c].y, options.margin - 1e-3);
      ASSERT_LE(corners[c].y, options.height - 1 - options.margin + 1e-3);
      cx += corners[c].x / 4;
      cy += corners[c].y / 4;
    }
    for (int c = 0; c < 4; ++c) {
      // 3 px inside the corner: the corner's colour; 3 px outside: black.
      const double dx = cx - corners[c].x, dy = cy - corners[c].y, n = std::hypot(dx, dy);
      const cv::Point in(cvRound(corners[c].x + 3 * dx / n), cvRound(corners[c].y + 3 * dy / n));
      const cv::Point out(cvRound(corners[c].x - 3 * dx / n), cvRound(corners[c].y - 3 * dy / n));
      const cv::Vec3b pin = frame.at<cv::Vec3b>(in), pout = frame.at<cv::Vec3b>(out);
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(pin[k], expected[c][k], 40) << "trial " << trial << " corner " << c;
        EXPECT_LT(pout[k], 40) << "trial " << trial << " corner " << c;
      }
    }
    // The warped sign covers the quad's area.
    std::vector<cv::Point2f> quad;
    for (const Point2f& p : corners) quad.emplace_back(p.x, p.y);
    EXPECT_NEAR(cv::sum(alpha)[0], cv::contourArea(quad), 0.02 * cv::contourArea(quad) + 50);
  }
}

SynthSetOptions tiny_set(std::uint64_t seed) {
  SynthSetOptions o;
  o.backgrounds = KG_OPENCV_DATA_DIR;
  o.seed = seed;
  o.signs = 3;
  o.frames = 8;
  o.sign_free_fraction = 0.25;
  // Large, mildly turned, unoccluded signs: the detector should find them.
  o.frame.min_size = 300;
  o.frame.max_size = 360;
  o.frame.max_yaw_deg = 20;
  o.frame.max_pitch_deg = 15;
  o.frame.max_roll_deg = 10;
  o.frame.occlusion_probability = 0;
  o.frame.max_blur_sigma = 0.8;
  o.frame.max_noise_sigma = 2;
  o.frame.min_gain = 0.85;
  o.frame.max_gain = 1.1;
  return o;
}

TEST(SynthSet, FramesAreAFunctionOfTheSeedAndTheManifestRoundTrips) {
  SynthManifest m1, m2, m3;
  SynthSetImages i1, i2, i3;
  ASSERT_TRUE(render_synth_set(tiny_set(5), m1, i1).is_ok());
  ASSERT_TRUE(render_synth_set(tiny_set(5), m2, i2).is_ok());
  ASSERT_TRUE(render_synth_set(tiny_set(6), m3, i3).is_ok());
  ASSERT_EQ(i1.frames.size(), 8u);
  int sign_free = 0, differ = 0;
  for (std::size_t f = 0; f < i1.frames.size(); ++f) {
    EXPECT_TRUE(same(i1.frames[f], i2.frames[f])) << f;
    differ += !same(i1.frames[f], i3.frames[f]);
    EXPECT_EQ(i1.frames[f].cols, 640);
    EXPECT_EQ(i1.frames[f].rows, 480);
    const SynthFrameInfo& info = m1.frames[f].info;
    sign_free += info.sign < 0;
    if (info.sign < 0) continue;
    // The manifest's corners are the sign's outline under its homography.
    Point2f outline[4];
    sign_outline(i1.signs[static_cast<std::size_t>(info.sign)].size(), outline);
    for (int c = 0; c < 4; ++c) {
      const Point2f p = kg::apply(info.homography, outline[c]);
      EXPECT_NEAR(p.x, info.corners[c].x, 1e-3);
      EXPECT_NEAR(p.y, info.corners[c].y, 1e-3);
    }
  }
  EXPECT_EQ(sign_free, 2);
  EXPECT_EQ(differ, 8);

  SynthManifest parsed;
  ASSERT_TRUE(parse_manifest(manifest_text(m1), parsed).is_ok());
  ASSERT_EQ(parsed.frames.size(), m1.frames.size());
  ASSERT_EQ(parsed.signs.size(), 3u);
  EXPECT_EQ(parsed.signs[1].name, m1.signs[1].name);
  for (std::size_t f = 0; f < parsed.frames.size(); ++f) {
    EXPECT_EQ(parsed.frames[f].file, m1.frames[f].file);
    EXPECT_EQ(parsed.frames[f].info.sign, m1.frames[f].info.sign);
    for (int k = 0; k < 9; ++k)
      EXPECT_EQ(parsed.frames[f].info.homography[k], m1.frames[f].info.homography[k]);
    for (int c = 0; c < 4; ++c)
      EXPECT_EQ(parsed.frames[f].info.corners[c].x, m1.frames[f].info.corners[c].x);
  }
  SynthManifest bad;
  EXPECT_FALSE(parse_manifest("not a manifest\n", bad).is_ok());
  EXPECT_FALSE(
      parse_manifest("keygraph-synth 1\nsign 0 a a.png 10 10\nframe f.png sign 3\n", bad).is_ok());
  EXPECT_FALSE(
      parse_manifest("keygraph-synth 1\nsign 0 a a.png 10 10\nframe f.png sign 0\n", bad).is_ok());
  EXPECT_FALSE(
      parse_manifest("keygraph-synth 1\nsign 0 a a.png 10 10\nframe f.png sign -1 x 1\n", bad)
          .is_ok());
}

TEST(SynthEval, ScoresFollowTheRules) {
  SynthFrameInfo truth;
  truth.sign = 12;
  truth.homography = {0.5, 0, 100, 0, 0.5, 50, 0, 0, 1};
  const cv::Size size(201, 101);
  const auto shifted = [&](double dx) {
    Homography h = truth.homography;
    h[2] += dx;
    return h;
  };
  SynthCase c;
  // Index of signs 10..19: sign 12 is model 2.
  score_synth_frame({{2, truth.homography}}, truth, size, 10, c);
  EXPECT_TRUE(c.found);
  EXPECT_NEAR(c.corner_error, 0, 1e-9);
  EXPECT_EQ(c.false_detections, 0);
  score_synth_frame({{2, shifted(12)}, {2, shifted(-6)}, {3, truth.homography}}, truth, size, 10,
                    c);
  EXPECT_TRUE(c.found);  // the better of the two model-2 detections, 6 px
  EXPECT_NEAR(c.corner_error, 6, 1e-4);
  EXPECT_EQ(c.detections, 3);
  EXPECT_EQ(c.false_detections, 2);  // the 12 px one and the wrong model
  score_synth_frame({{2, shifted(10.5)}}, truth, size, 10, c);
  EXPECT_FALSE(c.found);
  EXPECT_EQ(c.false_detections, 1);
  SynthFrameInfo none;
  score_synth_frame({{0, truth.homography}}, none, size, 0, c);
  EXPECT_FALSE(c.found);
  EXPECT_EQ(c.false_detections, 1);

  // Tallies over constructed cases.
  SynthEvalOptions options;
  options.methods = {"m"};
  std::vector<SynthCase> cases(4);
  for (SynthCase& k : cases) {
    k.method = "m";
    k.index_size = 10;
  }
  cases[0] = {"m", 10, 0, 0, 1, true, 2.0, 1, 0, 10.0};
  cases[1] = {"m", 10, 0, 1, 2, true, 5.0, 2, 1, 30.0};
  cases[2] = {"m", 10, 0, 2, 3, false, -1, 0, 0, 20.0};
  cases[3] = {"m", 10, 0, 3, -1, false, -1, 1, 1, 40.0};
  const std::vector<SynthRow> rows = synth_tallies(cases, options);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].frames, 4);
  EXPECT_EQ(rows[0].sign_frames, 3);
  EXPECT_EQ(rows[0].within10, 2);
  EXPECT_EQ(rows[0].within3, 1);
  EXPECT_EQ(rows[0].false_detections, 2);
  EXPECT_EQ(rows[0].sign_free_with_false, 1);
  EXPECT_DOUBLE_EQ(rows[0].median_corner_error, 5.0);
  EXPECT_DOUBLE_EQ(rows[0].median_ms, 30.0);
  EXPECT_DOUBLE_EQ(rows[0].mean_ms, 25.0);
}

TEST(SynthEval, ConfidenceThresholdsKeepTheConfidentDetections) {
  // Frame 0: its sign found at confidence 0.95 and a wrong model at 0.6;
  // frame 1: its sign found at 0.75; frame 2 (sign-free): a false one at 0.85.
  auto scored = [](bool right, double confidence) {
    SynthScoredDetection d;
    d.right = right;
    d.support.confidence = confidence;
    return d;
  };
  std::vector<SynthCase> cases(3);
  for (std::size_t i = 0; i < cases.size(); ++i) {
    cases[i].method = "keygraph";
    cases[i].index_size = 10;
    cases[i].frame = static_cast<int>(i);
    cases[i].sign = i < 2 ? static_cast<int>(i) : -1;
    cases[i].has_confidence = true;
  }
  cases[0].scored = {scored(true, 0.95), scored(false, 0.6)};
  cases[1].scored = {scored(true, 0.75)};
  cases[2].scored = {scored(false, 0.85)};
  // Frame 1 again, with a second right detection (at 0.7): false, as in
  // the main table. Baselines carry no confidence and are not tallied,
  // with detections or without.
  cases.push_back(cases[1]);
  cases.back().frame = 3;
  cases.back().scored.push_back(scored(true, 0.7));
  SynthCase baseline = cases[0];
  baseline.method = "orb";
  baseline.has_confidence = false;
  baseline.scored = {scored(true, -1)};
  cases.push_back(baseline);
  baseline.scored.clear();
  cases.push_back(baseline);
  const std::vector<SynthConfidenceRow> rows = synth_by_confidence(cases);
  const std::vector<double>& thresholds = synth_confidence_thresholds();
  ASSERT_EQ(rows.size(), thresholds.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const SynthConfidenceRow& r = rows[i];
    const double t = thresholds[i];
    EXPECT_EQ(r.method, "keygraph");
    EXPECT_DOUBLE_EQ(r.threshold, t);
    EXPECT_EQ(r.frames, 4);
    EXPECT_EQ(r.sign_frames, 3);
    EXPECT_EQ(r.found, (0.95 >= t ? 1 : 0) + 2 * (0.75 >= t ? 1 : 0)) << t;
    // The repeated frame's two right ones: one found, the other false when
    // both are kept (or found alone at 0.7 <= t < 0.75: never here).
    const int second_right = 0.75 >= t && 0.7 >= t ? 1 : 0;
    EXPECT_EQ(r.false_detections, (0.6 >= t ? 1 : 0) + (0.85 >= t ? 1 : 0) + second_right) << t;
  }
}

TEST(SynthEval, KeygraphFindsTheSignsOfASmallGeneratedSet) {
  namespace fs = std::filesystem;
  const std::string dir = std::string(KG_TEST_OUTPUT_DIR) + "/synth_tiny";
  fs::remove_all(dir);
  SynthSetOptions set = tiny_set(3);
  set.directory = dir;
  ASSERT_TRUE(write_synth_set(set).is_ok());
  EXPECT_TRUE(fs::exists(dir + "/manifest.txt"));
  EXPECT_TRUE(fs::exists(dir + "/frames/0007.png"));
  EXPECT_FALSE(fs::exists(fs::path(dir).parent_path() / ".tmp-synth_tiny"));
  // A non-empty directory is never overwritten.
  EXPECT_FALSE(write_synth_set(set).is_ok());
  EXPECT_TRUE(fs::exists(dir + "/manifest.txt"));

  SynthEvalOptions options;
  options.directory = dir;
  options.index_sizes = {1, 3};
  std::vector<SynthCase> cases;
  const Status s = evaluate_synth(options, cases);
  ASSERT_TRUE(s.is_ok()) << s.message();
  ASSERT_EQ(cases.size(), 16u);  // 8 frames, 2 index sizes
  int found = 0, sign_frames = 0, false_on_sign_free = 0;
  for (const SynthCase& c : cases) {
    EXPECT_EQ(c.method, "keygraph");
    if (c.sign < 0) {
      false_on_sign_free += c.false_detections;
      continue;
    }
    ++sign_frames;
    found += c.found;
    // 300..360 px longer side for signs of 400..600: scale about 0.5 to 0.9.
    EXPECT_GT(c.scale, 0.35);
    EXPECT_LT(c.scale, 1.0);
    if (c.found) {
      EXPECT_LE(c.corner_error, 10.0);
    }
  }
  EXPECT_EQ(sign_frames, 12);
  EXPECT_GE(found, 10) << "of " << sign_frames;  // all 12 at commit time
  EXPECT_EQ(false_on_sign_free, 0);
  SynthEvalOptions missing;
  missing.directory = dir + "/nonexistent";
  EXPECT_FALSE(evaluate_synth(missing, cases).is_ok());
}

// The photometric refinement (format 6.2 appearances) on frames whose
// truth is exact: the same detections with and without the models'
// appearances in the index.
TEST(SynthEval, AppearanceBringsTheCornersWithinAPixel) {
  namespace fs = std::filesystem;
  const std::string dir = std::string(KG_TEST_OUTPUT_DIR) + "/synth_tiny_appearance";
  fs::remove_all(dir);
  SynthSetOptions set = tiny_set(3);
  set.directory = dir;
  ASSERT_TRUE(write_synth_set(set).is_ok());
  double median[2] = {0.0, 0.0};
  int found[2] = {0, 0};
  for (const int appearance_size : {0, 128}) {
    SynthEvalOptions options;
    options.directory = dir;
    options.index_sizes = {3};
    // The frontal configuration, where the effect was measured: with the
    // defaults' tilted views, check and completion the median worst corner
    // on this set is 1.04 px (docs/RESULTS.md, "Tilted views at 45
    // degrees by default"), just over what this test asserts.
    options.params = frontal_params();
    options.params.views.appearance_size = appearance_size;
    std::vector<SynthCase> cases;
    const Status s = evaluate_synth(options, cases);
    ASSERT_TRUE(s.is_ok()) << s.message();
    std::vector<double> errors;
    for (const SynthCase& c : cases) {
      if (c.found) errors.push_back(c.corner_error);
      for (const SynthScoredDetection& d : c.scored)
        EXPECT_EQ(d.support.appearance >= 0.0, appearance_size > 0);
    }
    ASSERT_FALSE(errors.empty());
    std::sort(errors.begin(), errors.end());
    const int k = appearance_size > 0 ? 1 : 0;
    median[k] = errors[errors.size() / 2];
    found[k] = static_cast<int>(errors.size());
    std::printf("appearance %d px: %d of 6 signs found, median worst-corner error %.2f px\n",
                appearance_size, found[k], median[k]);
  }
  EXPECT_GE(found[1], found[0]);
  EXPECT_LT(median[1], 1.0);
  EXPECT_LT(median[1], 0.5 * median[0]);
}

}  // namespace
}  // namespace kg
