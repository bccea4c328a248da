// The evaluation harness on the Oxford data (KG_DATA_DIR/oxford): the
// paper's protocol end to end, and parameter overrides by name.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/index/index_format.h"
#include "eval/oxford.h"
#include "eval/oxford_report.h"
#include "keygraph/param_text.h"
#include "support/data_dir.h"

namespace kg {
namespace {

TEST(OxfordEval, CentreCropsOfGrafAndBoatFoundInTheMildScenes) {
  KG_REQUIRE_DATA("oxford");
  OxfordEvalOptions options;
  options.dataset = test::data_dir("oxford");
  options.subsets = {"graf", "boat"};
  options.centre_crop = true;
  std::vector<OxfordCase> cases;
  const Status s = evaluate_oxford(options, cases);
  ASSERT_TRUE(s.is_ok()) << s.message();
  ASSERT_EQ(cases.size(), 10u);
  for (const OxfordCase& c : cases) {
    EXPECT_EQ(c.crop_x, c.subset == "graf" ? 250 : 275);
    if (c.degree > 3) continue;  // img2 and img3: mild viewpoint or zoom change
    EXPECT_TRUE(c.detected) << c.subset << " img" << c.degree;
    EXPECT_LT(c.corner_error, 3.0) << c.subset << " img" << c.degree;
  }
  // No wrong pose anywhere: a detection is right or absent.
  for (const OxfordCase& c : cases) {
    if (c.detected) {
      EXPECT_LT(c.corner_error, 10.0) << c.subset << " img" << c.degree;
    }
  }
}

// Where a pose is "wrong", the image may say the ground truth is: in boat's
// img6 (the strongest zoom) the homography misses parts of the scene by
// 10 to 20 px, and there the crop correlates with the scene far better
// under the pose found than under the ground truth (SIFT + RANSAC is as
// far off on the same crops; docs/RESULTS.md, "Wrong poses and the ground
// truth"). This holds the measurement to that: exact truths
// correlate highly, correct poses at least as well as the truth, and a
// wrong pose is wrong against the image only if it fits no better.
TEST(OxfordEval, WrongPosesOfBoatFitTheImageBetterThanItsGroundTruth) {
  KG_REQUIRE_DATA("oxford");
  OxfordEvalOptions options;
  options.dataset = test::data_dir("oxford");
  options.subsets = {"boat"};
  options.crops_per_subset = 5;
  std::vector<OxfordCase> cases;
  const Status s = evaluate_oxford(options, cases);
  ASSERT_TRUE(s.is_ok()) << s.message();
  ASSERT_EQ(cases.size(), 25u);
  int wrong = 0;
  for (const OxfordCase& c : cases) {
    const std::string where = "crop " + std::to_string(c.crop) + " img" + std::to_string(c.degree);
    ASSERT_GT(c.truth_correlation, -1.0) << where;  // measured on every positive case
    // img2..img5: the ground truth holds across each crop.
    if (c.degree <= 5) {
      EXPECT_GT(c.truth_correlation, 0.85) << where;
    }
    // Crop 4 (157, 302) in img6: the ground truth is off there.
    if (c.crop == 4 && c.degree == 6) {
      EXPECT_EQ(c.crop_x, 157) << where;
      EXPECT_LT(c.truth_correlation, 0.5) << where;
    }
    if (!c.detected) {
      EXPECT_EQ(c.found_correlation, -1.0) << where;
      continue;
    }
    EXPECT_GT(c.found_correlation, 0.8) << where;
    if (c.corner_error <= 3.0) {
      EXPECT_GE(c.found_correlation, c.truth_correlation - 0.01) << where;
    }
    if (c.corner_error > 10.0) {
      EXPECT_GT(c.found_correlation, c.truth_correlation + 0.15) << where;
      ++wrong;
    }
  }
  // The report lists each wrong pose on a line of its own, under a header
  // of four lines.
  const std::string text = oxford_wrong_poses_text(cases);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), wrong == 0 ? 0 : wrong + 4) << text;
}

// The paper's precision-recall measurement on graf's centre crop.
TEST(OxfordEval, CurvesOfKeygraphsAndKeypointsOnGraf) {
  KG_REQUIRE_DATA("oxford");
  OxfordEvalOptions options;
  options.dataset = test::data_dir("oxford");
  options.subsets = {"graf"};
  options.centre_crop = true;
  options.curves = true;
  // The frontal configuration (no tilted views, triangle check or circuit
  // completion): the curve joins the three searched lists, as its
  // selection does.
  options.params = frontal_params();
  // float32, as the curve selection: the curve at the index's threshold is
  // then exactly the detector's own selection.
  options.params.descriptor.encoding = DescriptorEncoding::kFloat32;
  // and exact search: the curve sweeps the threshold over every model arc.
  options.params.descriptor.max_search_leaves = 0;
  // and the single model image: with views the detector's per-query limits
  // (max_arc_matches) cut the far larger exact answer, so its selection is
  // no longer the whole threshold set.
  options.params.views.min_size = 0.f;
  std::vector<OxfordCase> cases;
  const Status s = evaluate_oxford(options, cases);
  ASSERT_TRUE(s.is_ok()) << s.message();
  ASSERT_EQ(cases.size(), 5u);
  const OxfordCurveGrids grids = oxford_curve_grids();
  std::size_t at = 0;
  while (at < grids.arc.size() && grids.arc[at] < 0.3 - 1e-9) ++at;
  ASSERT_LT(at, grids.arc.size());
  for (const OxfordCase& c : cases) {
    ASSERT_TRUE(c.has_curves);
    EXPECT_FALSE(c.curve_truncated);
    const CaseCurve& k = c.keygraph_curve;
    EXPECT_EQ(k.truth, c.sift_distance_curve.truth);
    EXPECT_GT(c.model_keypoints, 300);
    // Selecting by threshold is exactly what the detector's selection did.
    EXPECT_EQ(k.selected[at], c.correspondences) << "img" << c.degree;
    for (std::size_t i = 1; i < k.selected.size(); ++i) {
      EXPECT_GE(k.selected[i], k.selected[i - 1]);
      EXPECT_GE(k.recalled[i], k.recalled[i - 1]);
      EXPECT_LE(k.correct[i], k.selected[i]);
    }
    // Every selected pair at the largest SIFT distance: recall 1.
    EXPECT_EQ(c.sift_distance_curve.recalled.back(), c.sift_distance_curve.truth);
  }
  // img2 (mild viewpoint change) against img6 (strong): more true keypoint
  // correspondences, and keygraph correspondences far more precise.
  const OxfordCase& mild = cases[0];
  const OxfordCase& strong = cases[4];
  ASSERT_EQ(mild.degree, 2);
  ASSERT_EQ(strong.degree, 6);
  EXPECT_GT(mild.keygraph_curve.truth, 2 * strong.keygraph_curve.truth);
  EXPECT_GT(case_precision(mild.keygraph_curve, at), 0.05);
  EXPECT_GT(case_recall(mild.keygraph_curve, at), 0.5);
  EXPECT_GT(case_precision(mild.keygraph_curve, at), 3 * case_precision(strong.keygraph_curve, at));

  // The report: JSON summary, one CSV per curve, PNG plots.
  const std::string dir = std::string(KG_TEST_OUTPUT_DIR) + "/oxford_report";
  std::filesystem::remove_all(dir);
  platform::OutputSet report(dir, {});
  ASSERT_TRUE(write_oxford_report(report, dir, options, cases).is_ok());
  ASSERT_TRUE(report.commit().is_ok());
  for (const char* f : {"summary.json", "cases.csv", "pr-keygraph.png", "iterations-keygraph.png",
                        "pr-keygraph-degrees.png", "curves/keygraph-all-keygraph.csv",
                        "curves/keygraph-img2-sift-ratio.csv"}) {
    EXPECT_TRUE(std::filesystem::exists(dir + "/" + f)) << f;
  }
  std::ifstream in(dir + "/curves/keygraph-img2-keygraph.csv");
  std::string header, line;
  std::getline(in, header);
  EXPECT_EQ(header, "threshold,recall,precision,expected_iterations,recall_cases,precision_cases");
  for (std::size_t i = 0; i <= at; ++i) std::getline(in, line);
  std::stringstream row(line);
  double threshold = 0, recall = 0, precision = 0;
  char comma = 0;
  row >> threshold >> comma >> recall >> comma >> precision;
  EXPECT_NEAR(threshold, 0.3, 1e-9);
  EXPECT_NEAR(recall, case_recall(mild.keygraph_curve, at), 1e-9);
  EXPECT_NEAR(precision, case_precision(mild.keygraph_curve, at), 1e-9);
  const std::vector<OxfordIterationRow> iterations = oxford_iterations(cases, options);
  ASSERT_FALSE(iterations.empty());
  EXPECT_EQ(iterations.back().group, "all");
  EXPECT_EQ(iterations.back().h_keygraph, 2);
  EXPECT_EQ(iterations.back().h_keypoint, 4);
  // Every case is found or lost at exactly one stage; repeatability is a fraction.
  for (const OxfordLimitRow& r : oxford_limits(cases, options)) {
    EXPECT_EQ(r.found + r.too_few_at_max + r.threshold_limited + r.pose_limited, r.cases)
        << r.group;
    EXPECT_GT(r.scene_repeatability, 0.2) << r.group;
    EXPECT_LE(r.scene_repeatability, 1.0) << r.group;
    EXPECT_NEAR(r.scene_repeatability_cubed, std::pow(r.scene_repeatability, 3), 0.1) << r.group;
  }
  for (const OxfordCase& c : cases) {
    EXPECT_LE(c.model_repeated, c.model_inside);
    EXPECT_LE(c.scene_repeated, c.scene_inside);
    EXPECT_GT(c.scene_inside, 0);
  }
}

TEST(OxfordEvalErrors, MissingDatasetIsAnError) {
  OxfordEvalOptions options;
  options.dataset = "/nonexistent/oxford";
  std::vector<OxfordCase> cases;
  EXPECT_FALSE(evaluate_oxford(options, cases).is_ok());
}

TEST(OxfordEval, ReadsTextHomography) {
  KG_REQUIRE_DATA("oxford");
  Homography h;
  ASSERT_TRUE(read_homography(test::data_dir("oxford") + "/graf/H1to3p", h).is_ok());
  EXPECT_NEAR(h[0], 0.76285898, 1e-8);
  EXPECT_NEAR(h[2], 225.67123, 1e-5);
  EXPECT_EQ(h[8], 1.0);
  EXPECT_FALSE(read_homography("/nonexistent", h).is_ok());
}

TEST(ParamOverrides, SetsValidatesAndRejects) {
  Params p;
  ASSERT_TRUE(set_param(p, "descriptor.similarity_threshold=0.5").is_ok());
  EXPECT_FLOAT_EQ(p.descriptor.similarity_threshold, 0.5f);
  ASSERT_TRUE(set_param(p, "graph.scene_sampling=random").is_ok());
  EXPECT_EQ(p.graph.scene_sampling, SceneSampling::kRandom);
  ASSERT_TRUE(set_param(p, "ransac.max_iterations=500").is_ok());
  EXPECT_EQ(p.ransac.max_iterations, 500);
  EXPECT_FALSE(set_param(p, "ransac.max_iterations=5x").is_ok());
  EXPECT_FALSE(set_param(p, "no.such=1").is_ok());
  EXPECT_FALSE(set_param(p, "missing-equals").is_ok());
  ASSERT_TRUE(set_param(p, "graph.min_distance=200").is_ok());  // parses ...
  EXPECT_FALSE(format::validate_params(p).is_ok());             // ... but min > max
  EXPECT_GT(param_names().size(), 20u);
}

}  // namespace
}  // namespace kg
