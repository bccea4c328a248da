// The ground-truth manifest of eval --truth (eval/truth_manifest.h) on good
// and bad lines and files, and the scoring of one scene
// (eval/truth_eval.h) on detections with known answers.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "eval/truth_eval.h"
#include "eval/truth_manifest.h"
#include "support/temp_dir.h"

namespace kg {
namespace {

TEST(TruthManifestLine, CornersWithOneOrSeveralModelNames) {
  TruthScene s;
  std::string error;
  ASSERT_TRUE(parse_truth_line(
      R"({"scene": "f/1.jpg", "instances": [{"model": "exit-left", "corners": [[1, 2], [30, 2], [30, 20], [1, 20]]},
          {"model": ["exit-left", "exit-right"], "corners": [[50, 50], [50, 60], [70, 60], [70, 50.5]]}]})",
      s, error))
      << error;
  EXPECT_EQ(s.scene, "f/1.jpg");
  ASSERT_EQ(s.instances.size(), 2u);
  EXPECT_EQ(s.instances[0].models, std::vector<std::string>{"exit-left"});
  EXPECT_EQ(s.instances[1].models, (std::vector<std::string>{"exit-left", "exit-right"}));
  EXPECT_FALSE(s.instances[1].has_homography);
  EXPECT_FLOAT_EQ(s.instances[0].corners[2].x, 30.f);
  EXPECT_FLOAT_EQ(s.instances[1].corners[3].y, 50.5f);
  EXPECT_TRUE(s.search.empty());
}

TEST(TruthManifestLine, HomographyIsNormalisedAndSearchKept) {
  TruthScene s;
  std::string error;
  ASSERT_TRUE(parse_truth_line(
      R"({"scene": "b.png", "search": ["adam"], "instances": [{"model": "adam", "homography": [2, 0, 10, 0, 2, 20, 0, 0, 2]}]})",
      s, error))
      << error;
  ASSERT_EQ(s.instances.size(), 1u);
  EXPECT_TRUE(s.instances[0].has_homography);
  EXPECT_DOUBLE_EQ(s.instances[0].homography[0], 1.0);
  EXPECT_DOUBLE_EQ(s.instances[0].homography[2], 5.0);
  EXPECT_DOUBLE_EQ(s.instances[0].homography[8], 1.0);
  EXPECT_EQ(s.search, std::vector<std::string>{"adam"});
}

TEST(TruthManifestLine, EmptyInstancesIsANegativeScene) {
  TruthScene s;
  std::string error;
  ASSERT_TRUE(parse_truth_line(R"({"scene": "n.jpg", "instances": []})", s, error)) << error;
  EXPECT_TRUE(s.instances.empty());
}

TEST(TruthManifestLine, BadLinesSayWhatIsWrong) {
  const std::pair<const char*, const char*> bad[] = {
      {R"({"scene": "a.jpg", "instances": [)", "not valid JSON"},
      {R"([1, 2])", "JSON object"},
      {R"({"instances": []})", "\"scene\""},
      {R"({"scene": "", "instances": []})", "\"scene\""},
      {R"({"scene": 3, "instances": []})", "\"scene\""},
      {R"({"scene": "a.jpg"})", "\"instances\""},
      {R"({"scene": "a.jpg", "instances": {}})", "\"instances\""},
      {R"({"scene": "a.jpg", "instances": [], "colour": 1})", "unknown field \"colour\""},
      {R"({"scene": "a.jpg", "instances": [{"corners": [[0,0],[1,0],[1,1],[0,1]]}]})",
       "no \"model\""},
      {R"({"scene": "a.jpg", "instances": [{"model": [], "corners": [[0,0],[1,0],[1,1],[0,1]]}]})",
       "\"model\""},
      {R"({"scene": "a.jpg", "instances": [{"model": ["a", 2], "corners": [[0,0],[1,0],[1,1],[0,1]]}]})",
       "\"model\""},
      {R"({"scene": "a.jpg", "instances": [{"model": "a", "corners": [[0,0],[1,0],[1,1]]}]})",
       "four [x, y] points"},
      {R"({"scene": "a.jpg", "instances": [{"model": "a", "corners": [[0,0],[1,0],[1,1],[0,1],[2,2]]}]})",
       "four [x, y] points"},
      {R"({"scene": "a.jpg", "instances": [{"model": "a", "corners": [[0,0],[1,0],[1,"1"],[0,1]]}]})",
       "four [x, y] points"},
      {R"({"scene": "a.jpg", "instances": [{"model": "a", "corners": [[0,0],[1,0,5],[1,1],[0,1]]}]})",
       "four [x, y] points"},
      {R"({"scene": "a.jpg", "instances": [{"model": "a", "corners": [[0,0],[1,1],[1,0],[0,1]]}]})",
       "cross"},
      {R"({"scene": "a.jpg", "instances": [{"model": "a", "corners": [[0,0],[1,1],[2,2],[3,3]]}]})",
       "no area"},
      {R"({"scene": "a.jpg", "instances": [{"model": "a"}]})", "either"},
      {R"({"scene": "a.jpg", "instances": [{"model": "a", "corners": [[0,0],[1,0],[1,1],[0,1]], "homography": [1,0,0,0,1,0,0,0,1]}]})",
       "either"},
      {R"({"scene": "a.jpg", "instances": [{"model": "a", "homography": [1,0,0,0,1,0,0,0]}]})",
       "9 numbers"},
      {R"({"scene": "a.jpg", "instances": [{"model": "a", "homography": [1,2,3,2,4,6,0,0,1]}]})",
       "singular"},
      {R"({"scene": "a.jpg", "instances": [{"model": ["a", "b"], "homography": [1,0,0,0,1,0,0,0,1]}]})",
       "one model name"},
      {R"({"scene": "a.jpg", "instances": [{"model": "a", "corners": [[0,0],[1,0],[1,1],[0,1]], "size": 2}]})",
       "unknown instance field"},
      {R"({"scene": "a.jpg", "instances": [], "search": 5})", "\"search\""},
      {R"({"scene": "a.jpg", "instances": [7]})", "object"},
  };
  for (const auto& [line, expected] : bad) {
    TruthScene s;
    std::string error;
    EXPECT_FALSE(parse_truth_line(line, s, error)) << line;
    EXPECT_NE(error.find(expected), std::string::npos) << line << " -> " << error;
  }
}

class TruthManifestFile : public ::testing::Test {
 protected:
  // A directory of its own per test: ctest runs the tests of this fixture as
  // parallel processes, which must not write one shared manifest.
  void SetUp() override { ASSERT_FALSE(dir().empty()) << "no temporary directory"; }
  const std::filesystem::path& dir() const { return temp_.path(); }
  std::string write(const std::string& text) {
    const std::string path = (dir() / "m.jsonl").string();
    std::ofstream(path) << text;
    return path;
  }
  kg::test::TempDir temp_;
};

TEST_F(TruthManifestFile, PathsAreRelativeToTheManifestAndCommentsSkipped) {
  const std::string path = write(
      "# a comment\n\n"
      R"({"scene": "frames/1.jpg", "instances": []})"
      "\r\n"
      R"({"scene": "/abs/2.jpg", "instances": []})"
      "\n");
  TruthManifest m;
  ASSERT_TRUE(read_truth_manifest(path, m));
  ASSERT_EQ(m.scenes.size(), 2u);
  EXPECT_EQ(m.scenes[0].line, 3);
  EXPECT_EQ(m.scenes[0].path, (dir() / "frames/1.jpg").string());
  EXPECT_EQ(m.scenes[1].path, "/abs/2.jpg");
  EXPECT_EQ(m.scenes[1].line, 4);
}

TEST_F(TruthManifestFile, ErrorsNameTheFileAndLine) {
  const std::string path =
      write(R"({"scene": "1.jpg", "instances": []})"
            "\n"
            R"({"scene": "2.jpg", "instances": [{"model": "a", "corners": [[0, 0], [1, 1]]}]})"
            "\n");
  TruthManifest m;
  const Status s = read_truth_manifest(path, m);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.message(), path + ":2: \"corners\" must be four [x, y] points");
  EXPECT_FALSE(read_truth_manifest(write("# only a comment\n"), m));
  EXPECT_FALSE(read_truth_manifest((dir() / "missing.jsonl").string(), m));
}

TEST(TruthModels, UnknownNamesInInstancesAndSearch) {
  TruthScene s;
  std::string error;
  ASSERT_TRUE(parse_truth_line(
      R"({"scene": "a.jpg", "search": ["b"], "instances": [{"model": ["a", "c"], "corners": [[0,0],[1,0],[1,1],[0,1]]}]})",
      s, error));
  EXPECT_TRUE(check_truth_models(s, {"a", "b", "c"}, error));
  EXPECT_FALSE(check_truth_models(s, {"a", "b"}, error));
  EXPECT_EQ(error, "unknown model \"c\"");
  EXPECT_FALSE(check_truth_models(s, {"a", "c"}, error));
  EXPECT_EQ(error, "unknown model \"b\"");
}

// Scoring one scene: models 0 ("left") and 1 ("right") of 100 x 50 px.
class ScoreScene : public ::testing::Test {
 protected:
  std::vector<TruthModel> models_ = {{"left", 100, 50}, {"right", 100, 50}};
  // An instance at half the model's size, corners clicked from the bottom
  // right, anticlockwise.
  TruthQuad instance(std::vector<int> accepted) {
    TruthQuad t;
    t.models = std::move(accepted);
    t.corners[0] = {60, 45};
    t.corners[1] = {60, 20};
    t.corners[2] = {10, 20};
    t.corners[3] = {10, 45};
    return t;
  }
  FoundQuad detection(int model, float dx) {
    FoundQuad f;
    f.model = model;
    f.corners[0] = {10 + dx, 20};
    f.corners[1] = {60 + dx, 20};
    f.corners[2] = {60 + dx, 45};
    f.corners[3] = {10 + dx, 45};
    return f;
  }
  void score(const std::vector<FoundQuad>& found, const std::vector<TruthQuad>& truth) {
    score_truth_scene(found, truth, models_, 640, 480, 10, 0.5, cases_, kinds_, instance_of_);
  }
  std::vector<TruthCase> cases_;
  std::vector<DetectionKind> kinds_;
  std::vector<int> instance_of_;
};

TEST_F(ScoreScene, FoundInAnyCornerOrderWithAnAcceptableName) {
  score({detection(1, 3)}, {instance({0, 1})});
  ASSERT_EQ(cases_.size(), 1u);
  EXPECT_TRUE(cases_[0].found);
  EXPECT_NEAR(cases_[0].corner_error, 3.0, 1e-6);
  EXPECT_TRUE(cases_[0].found_iou);
  EXPECT_NEAR(cases_[0].iou, 47.0 / 53.0, 1e-6);
  EXPECT_NEAR(cases_[0].long_edge, 50.0, 1e-9);
  EXPECT_NEAR(cases_[0].scale, std::sqrt(50.0 * 25 / (100.0 * 50)), 1e-9);
  EXPECT_EQ(kinds_, std::vector<DetectionKind>{DetectionKind::kTrue});
  EXPECT_EQ(cases_[0].false_detections, 0);
}

TEST_F(ScoreScene, CornersAndIouDisagreeOnASmallShift) {
  // 12 px off: beyond the corner tolerance, but IoU 38/62 >= 0.5.
  score({detection(0, 12)}, {instance({0})});
  EXPECT_FALSE(cases_[0].found);
  EXPECT_TRUE(cases_[0].found_iou);
  EXPECT_EQ(kinds_[0], DetectionKind::kTrue);  // it lies on the instance
}

TEST_F(ScoreScene, WrongIdentityFalseAndDuplicateDetections) {
  score({detection(1, 0), detection(0, 0), detection(0, 1), detection(0, 300)}, {instance({0})});
  EXPECT_TRUE(cases_[0].found);
  EXPECT_EQ(kinds_[0], DetectionKind::kWrongIdentity);
  EXPECT_EQ(kinds_[1], DetectionKind::kTrue);
  EXPECT_EQ(kinds_[2], DetectionKind::kFalse);  // a second detection of the same instance
  EXPECT_EQ(kinds_[3], DetectionKind::kFalse);
  EXPECT_EQ(cases_[0].wrong_identity, 1);
  EXPECT_EQ(cases_[0].false_detections, 2);
  EXPECT_EQ(cases_[0].detections, 4);
}

TEST_F(ScoreScene, ANegativeSceneHasOneRow) {
  score({detection(0, 0)}, {});
  ASSERT_EQ(cases_.size(), 1u);
  EXPECT_EQ(cases_[0].detections, 1);
  EXPECT_EQ(cases_[0].false_detections, 1);
  EXPECT_FALSE(cases_[0].found);
}

TEST_F(ScoreScene, HomographyTruthGridError) {
  // Truth: model pixels scaled by 2 and shifted; the detection 4 px to the right.
  TruthQuad t;
  t.models = {0};
  t.has_homography = true;
  t.homography = {2, 0, 5, 0, 2, 7, 0, 0, 1};
  for (int c = 0; c < 4; ++c) {
    const Point2f m[4] = {{0, 0}, {99, 0}, {99, 49}, {0, 49}};
    t.corners[c] = kg::apply(t.homography, m[c]);
  }
  FoundQuad f;
  f.model = 0;
  f.homography = {2, 0, 9, 0, 2, 7, 0, 0, 1};
  for (int c = 0; c < 4; ++c) f.corners[c] = {t.corners[c].x + 4, t.corners[c].y};
  score({f}, {t});
  EXPECT_TRUE(cases_[0].found);
  EXPECT_NEAR(cases_[0].homography_error, 4.0, 1e-4);
}

}  // namespace
}  // namespace kg
