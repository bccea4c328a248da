// Limits::threads: the same detections and correspondences for any thread
// count, bit for bit, also when a frame reaches the correspondence cap or
// overflows the arc pool; nothing allocated per frame with workers either.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "core/keygraphs/keygraph.h"
#include "keygraph/detector.h"
#include "support/alloc_counter.h"
#include "support/opencv_scenes.h"
#include "support/test_data.h"

namespace kg {
namespace {

struct Fixture {
  test::InMemoryIndex built;
  std::vector<cv::Mat> scenes;
};

// The box and a graf1 crop (circuit completion on: the defaults), and
// scenes with one, the other, or neither.
const Fixture& fixture() {
  static Fixture f = [] {
    Fixture x;
    const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
    EXPECT_TRUE(
        test::build_in_memory({{"box", box}, {"graf", test::graf_crop()}}, Params{}, x.built));
    for (const char* name : {"box_in_scene.png", "graf3.png", "aero1.jpg"})
      x.scenes.push_back(test::load_gray(test::opencv_data(name)));
    return x;
  }();
  return f;
}

// Everything a frame's detection gives that must not depend on threads.
struct Outcome {
  std::vector<Detection> detections;
  std::vector<KeygraphMatch> matches;
  int correspondences = 0;
  long long arc_matches = 0;
  int ransac_iterations = 0;
  bool truncated_arc_matches = false, truncated_correspondences = false;
  bool truncated_detections = false;
};

Outcome detect(Detector& detector, const cv::Mat& scene) {
  Outcome o;
  DetectionList found;
  EXPECT_TRUE(detector.detect(test::view(scene), found));
  o.detections.assign(found.begin(), found.end());
  o.matches.assign(detector.last_matches().begin(), detector.last_matches().end());
  const DetectStats& s = detector.stats();
  o.correspondences = s.correspondences;
  o.arc_matches = s.arc_matches;
  o.truncated_arc_matches = s.truncated_arc_matches;
  o.truncated_correspondences = s.truncated_correspondences;
  o.ransac_iterations = s.ransac_iterations;
  o.truncated_detections = s.truncated_detections;
  return o;
}

void expect_same(const Outcome& a, const Outcome& b, int threads) {
  ASSERT_EQ(a.detections.size(), b.detections.size()) << threads << " threads";
  for (std::size_t i = 0; i < a.detections.size(); ++i) {
    EXPECT_EQ(a.detections[i].model_id, b.detections[i].model_id);
    EXPECT_EQ(a.detections[i].homography, b.detections[i].homography) << threads << " threads";
    EXPECT_EQ(a.detections[i].inliers, b.detections[i].inliers);
    EXPECT_EQ(a.detections[i].confidence, b.detections[i].confidence);
  }
  ASSERT_EQ(a.matches.size(), b.matches.size()) << threads << " threads";
  EXPECT_EQ(
      std::memcmp(a.matches.data(), b.matches.data(), a.matches.size() * sizeof(KeygraphMatch)), 0)
      << threads << " threads: the correspondences differ";
  EXPECT_EQ(a.correspondences, b.correspondences);
  EXPECT_EQ(a.arc_matches, b.arc_matches);
  EXPECT_EQ(a.truncated_arc_matches, b.truncated_arc_matches);
  EXPECT_EQ(a.truncated_correspondences, b.truncated_correspondences);
  EXPECT_EQ(a.ransac_iterations, b.ransac_iterations) << threads << " threads";
  EXPECT_EQ(a.truncated_detections, b.truncated_detections) << threads << " threads";
}

// Each scene with 1 thread and with 2, 3 and 4 under `limits`.
void expect_same_for_any_thread_count(Limits limits, const Fixture& f = fixture()) {
  limits = limits.for_frame(800, 640);
  limits.threads = 1;
  Detector one(f.built.index, limits);
  ASSERT_TRUE(one.status()) << one.status().message();
  std::vector<Outcome> reference;
  for (const cv::Mat& scene : f.scenes) reference.push_back(detect(one, scene));
  for (int threads : {2, 3, 4}) {
    limits.threads = threads;
    Detector many(f.built.index, limits);
    ASSERT_TRUE(many.status()) << many.status().message();
    for (int round = 0; round < 2; ++round)  // the workers are reused
      for (std::size_t i = 0; i < f.scenes.size(); ++i)
        expect_same(reference[i], detect(many, f.scenes[i]), threads);
  }
}

TEST(Threads, SameDetectionsForAnyThreadCount) {
  const Fixture& f = fixture();
  Limits limits = Limits{}.for_frame(800, 640);
  Detector one(f.built.index, limits);
  DetectionList found;
  ASSERT_TRUE(one.detect(test::view(f.scenes[0]), found));
  ASSERT_EQ(found.size(), 1u);  // the box: a real frame, not an empty one
  ASSERT_GT(one.stats().correspondences, 100);
  expect_same_for_any_thread_count(Limits{});
}

TEST(Threads, SameWhenTheCorrespondencesReachTheirCap) {
  Limits limits;
  limits.max_correspondences = 150;  // far fewer than box_in_scene gives
  expect_same_for_any_thread_count(limits);
  const Fixture& f = fixture();
  limits = limits.for_frame(800, 640);
  limits.threads = 3;
  Detector detector(f.built.index, limits);
  DetectionList found;
  ASSERT_TRUE(detector.detect(test::view(f.scenes[0]), found));
  EXPECT_TRUE(detector.stats().truncated_correspondences);
  EXPECT_EQ(detector.stats().correspondences, 150);
}

TEST(Threads, SameWhenTheArcPoolOverflows) {
  Limits limits;
  limits.max_arc_pool = 20000;  // a tenth of what box_in_scene's look-ups keep
  expect_same_for_any_thread_count(limits);
  const Fixture& f = fixture();
  limits = limits.for_frame(800, 640);
  limits.threads = 2;
  Detector detector(f.built.index, limits);
  DetectionList found;
  ASSERT_TRUE(detector.detect(test::view(f.scenes[0]), found));
  EXPECT_TRUE(detector.stats().truncated_arc_matches);
  // The arcs after the one that filled the pool are not searched (their
  // lists would be empty), so fewer model arcs are found than with room.
  Limits roomy = Limits{}.for_frame(800, 640);
  roomy.threads = 2;
  Detector unbounded(f.built.index, roomy);
  ASSERT_TRUE(unbounded.detect(test::view(f.scenes[0]), found));
  EXPECT_FALSE(unbounded.stats().truncated_arc_matches);
  EXPECT_LT(detector.stats().arc_matches, unbounded.stats().arc_matches / 2);
}

// The box twice and the graf1 crop: two models with an instance in
// box_in_scene, so the poses of several models run on the workers.
const Fixture& two_boxes() {
  static Fixture f = [] {
    Fixture x;
    const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
    EXPECT_TRUE(test::build_in_memory(
        {{"box", box}, {"graf", test::graf_crop()}, {"box again", box}}, Params{}, x.built));
    x.scenes = fixture().scenes;
    return x;
  }();
  return f;
}

TEST(Threads, SamePosesWhenSeveralModelsHaveInstances) {
  const Fixture& f = two_boxes();
  Limits limits = Limits{}.for_frame(800, 640);
  Detector one(f.built.index, limits);
  DetectionList found;
  ASSERT_TRUE(one.detect(test::view(f.scenes[0]), found));
  ASSERT_GE(found.size(), 1u);
  // Both boxes have enough correspondences for a pose task each (their
  // instances overlap: one is kept), so the poses ran on the workers.
  for (int m : {0, 2}) {
    int correspondences = 0;
    for (const KeygraphMatch& c : one.last_matches()) correspondences += c.model_id == m ? 1 : 0;
    ASSERT_GE(correspondences, sample_size(Params{}.graph.structure)) << "model " << m;
  }
  EXPECT_FALSE(one.stats().truncated_detections);
  expect_same_for_any_thread_count(Limits{}, f);
}

// The box alone: box_in_scene's one pose task runs on the caller's thread
// with the appearance alignment's sampling on the workers.
const Fixture& box_alone() {
  static Fixture f = [] {
    Fixture x;
    const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
    EXPECT_TRUE(test::build_in_memory({{"box", box}}, Params{}, x.built));
    x.scenes = fixture().scenes;
    return x;
  }();
  return f;
}

TEST(Threads, SamePoseWhenOneModelIsAlignedOnTheWorkers) {
  const Fixture& f = box_alone();
  Detector one(f.built.index, Limits{}.for_frame(800, 640));
  DetectionList found;
  ASSERT_TRUE(one.detect(test::view(f.scenes[0]), found));
  ASSERT_EQ(found.size(), 1u);
  EXPECT_GE(found[0].appearance, 0.0);  // the appearance was aligned
  expect_same_for_any_thread_count(Limits{}, f);
}

TEST(Threads, SamePosesWhenTheDetectionsReachTheirCap) {
  // One detection: the second box's instance is one too many for one
  // thread, which then stops that model's attempts.
  Limits limits;
  limits.max_detections = 1;
  const Fixture& f = two_boxes();
  Detector one(f.built.index, limits.for_frame(800, 640));
  DetectionList found;
  ASSERT_TRUE(one.detect(test::view(f.scenes[0]), found));
  ASSERT_EQ(found.size(), 1u);
  EXPECT_TRUE(one.stats().truncated_detections);
  expect_same_for_any_thread_count(limits, f);
}

TEST(Threads, NothingAllocatedPerFrame) {
  const Fixture& f = fixture();
  Limits limits = Limits{}.for_frame(800, 640);
  const std::size_t one = Detector::workspace_bytes(f.built.index, limits);
  limits.threads = 2;
  const std::size_t two = Detector::workspace_bytes(f.built.index, limits);
  EXPECT_GT(two, one);  // the second thread's share
  std::printf("workspace at 800x640: %zu bytes with 1 thread, %zu with 2\n", one, two);
  Detector detector(f.built.index, limits);
  DetectionList found;
  ASSERT_TRUE(detector.detect(test::view(f.scenes[0]), found));  // warm
  const test::AllocationCounter counter;
  for (int run = 0; run < 6; ++run)
    ASSERT_TRUE(detector.detect(test::view(f.scenes[static_cast<std::size_t>(run) % 3]), found));
  EXPECT_EQ(counter.count(), 0);
  EXPECT_EQ(detector.workspace_used(), detector.workspace_bytes());
}

TEST(Threads, CountOutOfRangeIsRefused) {
  const Fixture& f = fixture();
  Limits limits;
  limits.threads = 0;
  EXPECT_EQ(Detector(f.built.index, limits).status().code(), StatusCode::kInvalidArgument);
  limits.threads = 65;
  EXPECT_EQ(Detector(f.built.index, limits).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace kg
