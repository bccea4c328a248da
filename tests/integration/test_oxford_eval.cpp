// The evaluation harness on the Oxford data (../shared/data/oxford): the
// paper's protocol end to end, and parameter overrides by name.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "build/oxford.h"
#include "build/param_overrides.h"
#include "core/index_format.h"

namespace kg {
namespace {

TEST(OxfordEval, CentreCropsOfGrafAndBoatFoundInTheMildScenes) {
  OxfordEvalOptions options;
  options.dataset = std::string(KG_SHARED_DATA_DIR) + "/oxford";
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

TEST(OxfordEval, MissingDatasetIsAnError) {
  OxfordEvalOptions options;
  options.dataset = "/nonexistent/oxford";
  std::vector<OxfordCase> cases;
  EXPECT_FALSE(evaluate_oxford(options, cases).is_ok());
}

TEST(OxfordEval, ReadsTextHomography) {
  Homography h;
  ASSERT_TRUE(read_homography(std::string(KG_SHARED_DATA_DIR) + "/oxford/graf/H1to3p", h).is_ok());
  EXPECT_NEAR(h[0], 0.76285898, 1e-8);
  EXPECT_NEAR(h[2], 225.67123, 1e-5);
  EXPECT_EQ(h[8], 1.0);
  EXPECT_FALSE(read_homography("/nonexistent", h).is_ok());
}

TEST(ParamOverrides, SetsValidatesAndRejects) {
  Params p;
  ASSERT_TRUE(apply_param_override("descriptor.similarity_threshold=0.5", p).is_ok());
  EXPECT_FLOAT_EQ(p.descriptor.similarity_threshold, 0.5f);
  ASSERT_TRUE(apply_param_override("graph.scene_sampling=random", p).is_ok());
  EXPECT_EQ(p.graph.scene_sampling, SceneSampling::kRandom);
  ASSERT_TRUE(apply_param_override("ransac.max_iterations=500", p).is_ok());
  EXPECT_EQ(p.ransac.max_iterations, 500);
  EXPECT_FALSE(apply_param_override("ransac.max_iterations=5x", p).is_ok());
  EXPECT_FALSE(apply_param_override("no.such=1", p).is_ok());
  EXPECT_FALSE(apply_param_override("missing-equals", p).is_ok());
  ASSERT_TRUE(apply_param_override("graph.min_distance=200", p).is_ok());  // parses ...
  EXPECT_FALSE(format::validate_params(p).is_ok());                        // ... but min > max
  EXPECT_GT(param_names().size(), 20u);
}

}  // namespace
}  // namespace kg
