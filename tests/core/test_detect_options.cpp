// DetectOptions: the runtime settings a detector takes without rebuilding
// the index (keygraph/detector.h), on opencv-doc's box in box_in_scene and
// graf1 -> graf3 with one two-model index.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/index/kdtree.h"
#include "keygraph/detector.h"
#include "keygraph/param_text.h"
#include "keygraph/simd.h"
#include "support/alloc_counter.h"
#include "support/opencv_scenes.h"
#include "support/simd_scope.h"
#include "support/test_data.h"

namespace kg {
namespace {

struct Fixture {
  test::InMemoryIndex built;
  cv::Mat box_scene, graf_scene;
};

// The box (model 0) and a graf1 crop (model 1), built once.
const Fixture& fixture() {
  static Fixture f = [] {
    Fixture x;
    const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
    EXPECT_FALSE(box.empty());
    EXPECT_TRUE(
        test::build_in_memory({{"box", box}, {"graf", test::graf_crop()}}, Params{}, x.built));
    x.box_scene = test::load_gray(test::opencv_data("box_in_scene.png"));
    x.graf_scene = test::load_gray(test::opencv_data("graf3.png"));
    return x;
  }();
  return f;
}

Limits limits_for(const cv::Mat& a, const cv::Mat& b) {
  return Limits{}.for_frame(std::max(a.cols, b.cols), std::max(a.rows, b.rows));
}

std::vector<int> found_models(Detector& detector, const cv::Mat& scene) {
  DetectionList found;
  EXPECT_TRUE(detector.detect(test::view(scene), found));
  std::vector<int> ids;
  for (const Detection& d : found) ids.push_back(d.model_id);
  return ids;
}

TEST(DetectOptions, DefaultToTheIndexParameters) {
  const Fixture& f = fixture();
  const ModelIndex& index = f.built.index;
  const DetectOptions o = DetectOptions::from(index);
  const Params& p = index.params();
  EXPECT_EQ(o.ransac.seed, p.ransac.seed);
  EXPECT_EQ(o.ransac.max_iterations, p.ransac.max_iterations);
  EXPECT_EQ(o.ransac.min_triangle_correlation, p.ransac.min_triangle_correlation);
  EXPECT_EQ(o.max_search_leaves, p.descriptor.max_search_leaves);
  EXPECT_EQ(o.search_reference_models, p.descriptor.search_reference_models);
  EXPECT_EQ(o.min_confidence, 0.0);
  EXPECT_EQ(o.models, nullptr);

  // A detector without options and one given the index's find the same.
  const Limits limits = limits_for(f.box_scene, f.graf_scene);
  Detector implicit(index, limits), explicit_options(index, limits, o);
  ASSERT_TRUE(implicit.status()) << implicit.status().message();
  ASSERT_TRUE(explicit_options.status()) << explicit_options.status().message();
  DetectionList a, b;
  ASSERT_TRUE(implicit.detect(test::view(f.box_scene), a));
  ASSERT_TRUE(explicit_options.detect(test::view(f.box_scene), b));
  ASSERT_EQ(a.size(), 1u);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(a[0].homography, b[0].homography);
  EXPECT_EQ(implicit.options().ransac.seed, p.ransac.seed);
}

TEST(DetectOptions, ModelsToSearch) {
  const Fixture& f = fixture();
  const ModelIndex& index = f.built.index;
  Detector detector(index, limits_for(f.box_scene, f.graf_scene));
  ASSERT_TRUE(detector.status());
  EXPECT_EQ(found_models(detector, f.box_scene), std::vector<int>{0});
  EXPECT_EQ(found_models(detector, f.graf_scene), std::vector<int>{1});

  // Only the graf crop: the box is no longer found, the graf still is.
  DetectOptions o = DetectOptions::from(index);
  const std::int32_t graf_only[] = {1};
  o.models = graf_only;
  o.model_count = 1;
  ASSERT_TRUE(detector.set_options(o));
  EXPECT_FALSE(detector.searches_model(0));
  EXPECT_TRUE(detector.searches_model(1));
  EXPECT_EQ(detector.options().models, nullptr);  // the array is not kept
  EXPECT_TRUE(found_models(detector, f.box_scene).empty());
  EXPECT_EQ(found_models(detector, f.graf_scene), std::vector<int>{1});
  for (const KeygraphMatch& m : detector.last_matches()) EXPECT_EQ(m.model_id, 1);

  // An empty list searches nothing; nullptr every model again.
  o.model_count = 0;
  ASSERT_TRUE(detector.set_options(o));
  EXPECT_TRUE(found_models(detector, f.box_scene).empty());
  o.models = nullptr;
  ASSERT_TRUE(detector.set_options(o));
  EXPECT_EQ(found_models(detector, f.box_scene), std::vector<int>{0});
}

TEST(DetectOptions, ConfidenceFloorDropsLessLikelyDetections) {
  const Fixture& f = fixture();
  const ModelIndex& index = f.built.index;
  Detector detector(index, limits_for(f.box_scene, f.graf_scene));
  DetectionList found;
  ASSERT_TRUE(detector.detect(test::view(f.box_scene), found));
  ASSERT_EQ(found.size(), 1u);
  const double confidence = found[0].confidence;
  ASSERT_GT(confidence, 0.0);
  ASSERT_LT(confidence, 1.0);
  DetectOptions o = DetectOptions::from(index);
  o.min_confidence = confidence;  // kept: at the floor
  ASSERT_TRUE(detector.set_options(o));
  ASSERT_TRUE(detector.detect(test::view(f.box_scene), found));
  EXPECT_EQ(found.size(), 1u);
  o.min_confidence = std::nextafter(confidence, 2.0);  // dropped: just below
  ASSERT_TRUE(detector.set_options(o));
  ASSERT_TRUE(detector.detect(test::view(f.box_scene), found));
  EXPECT_TRUE(found.empty());
}

TEST(DetectOptions, SearchEffortAndSeedTakeEffect) {
  const Fixture& f = fixture();
  const ModelIndex& index = f.built.index;
  Detector detector(index, limits_for(f.box_scene, f.graf_scene));
  DetectionList found;
  ASSERT_TRUE(detector.detect(test::view(f.box_scene), found));
  const long long budgeted = detector.stats().arc_matches;
  // The exact search (no leaf budget) finds at least every arc the budget did.
  DetectOptions o = DetectOptions::from(index);
  o.max_search_leaves = 0;
  ASSERT_TRUE(detector.set_options(o));
  ASSERT_TRUE(detector.detect(test::view(f.box_scene), found));
  EXPECT_GT(detector.stats().arc_matches, budgeted);
  ASSERT_EQ(found.size(), 1u);

  // Another seed: the box is still found, and the same seed twice gives
  // the same pose.
  o = DetectOptions::from(index);
  o.ransac.seed = 12345;
  Detector a(index, limits_for(f.box_scene, f.graf_scene), o);
  Detector b(index, limits_for(f.box_scene, f.graf_scene), o);
  DetectionList fa, fb;
  ASSERT_TRUE(a.detect(test::view(f.box_scene), fa));
  ASSERT_TRUE(b.detect(test::view(f.box_scene), fb));
  ASSERT_EQ(fa.size(), 1u);
  ASSERT_EQ(fb.size(), 1u);
  EXPECT_EQ(fa[0].homography, fb[0].homography);
  EXPECT_EQ(a.options().ransac.seed, 12345u);
}

TEST(DetectOptions, TimeBudget) {
  const Fixture& f = fixture();
  const ModelIndex& index = f.built.index;
  const Limits limits = limits_for(f.box_scene, f.graf_scene);
  Detector plain(index, limits);
  DetectionList reference;
  ASSERT_TRUE(plain.detect(test::view(f.box_scene), reference));
  ASSERT_EQ(reference.size(), 1u);
  EXPECT_EQ(plain.stats().stopped_early, nullptr);

  // A budget no frame can meet: stopped after the keypoints, nothing found,
  // not an error, and nothing allocated.
  DetectOptions o = DetectOptions::from(index);
  o.time_budget_ms = 1e-6;
  Detector hurried(index, limits, o);
  DetectionList found;
  {
    const test::AllocationCounter counter;
    ASSERT_TRUE(hurried.detect(test::view(f.box_scene), found));
    EXPECT_EQ(counter.count(), 0);
  }
  EXPECT_TRUE(found.empty());
  ASSERT_NE(hurried.stats().stopped_early, nullptr);
  EXPECT_STREQ(hurried.stats().stopped_early, "keypoints");
  EXPECT_EQ(hurried.stats().correspondences, 0);

  // A budget every frame meets: the same detection as without one.
  o.time_budget_ms = 1e6;
  ASSERT_TRUE(hurried.set_options(o));
  ASSERT_TRUE(hurried.detect(test::view(f.box_scene), found));
  EXPECT_EQ(hurried.stats().stopped_early, nullptr);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].homography, reference[0].homography);

  o.time_budget_ms = -1.0;
  EXPECT_EQ(hurried.set_options(o).code(), StatusCode::kInvalidArgument);
  o.time_budget_ms = std::nan("");
  EXPECT_EQ(hurried.set_options(o).code(), StatusCode::kInvalidArgument);
  DetectOptions named;
  EXPECT_TRUE(set_detect_option(named, "time_budget_ms", "33"));
  EXPECT_EQ(named.time_budget_ms, 33.0);
}

TEST(DetectOptions, BadOptionsAreRefusedAndLeaveTheOldOnes) {
  const Fixture& f = fixture();
  const ModelIndex& index = f.built.index;
  Detector detector(index, limits_for(f.box_scene, f.graf_scene));
  DetectOptions o = DetectOptions::from(index);
  o.ransac.max_iterations = 0;
  Status s = detector.set_options(o);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("max_iterations"), std::string::npos) << s.message();
  EXPECT_EQ(detector.options().ransac.max_iterations, index.params().ransac.max_iterations);

  o = DetectOptions::from(index);
  const std::int32_t missing[] = {0, 2};
  o.models = missing;
  o.model_count = 2;
  s = detector.set_options(o);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("model id 2"), std::string::npos) << s.message();
  EXPECT_TRUE(detector.searches_model(1));

  o = DetectOptions::from(index);
  o.min_confidence = 1.5;
  EXPECT_FALSE(detector.set_options(o));
  o.min_confidence = std::nan("");
  EXPECT_FALSE(detector.set_options(o));

  // A detector constructed with bad options is failed and says why.
  o = DetectOptions::from(index);
  o.ransac.inlier_threshold = -1.0;
  Detector failed(index, Limits{}, o);
  EXPECT_EQ(failed.status().code(), StatusCode::kInvalidArgument);
  DetectionList found;
  EXPECT_FALSE(failed.detect(test::view(f.box_scene), found));
}

TEST(DetectOptions, SetOptionsAllocatesNothing) {
  const Fixture& f = fixture();
  const ModelIndex& index = f.built.index;
  Detector detector(index, limits_for(f.box_scene, f.graf_scene));
  DetectOptions o = DetectOptions::from(index);
  const std::int32_t graf_only[] = {1};
  o.models = graf_only;
  o.model_count = 1;
  o.max_search_leaves = 30;
  o.min_confidence = 0.2;
  DetectionList found;
  const test::AllocationCounter counter;
  ASSERT_TRUE(detector.set_options(o));
  ASSERT_TRUE(detector.detect(test::view(f.graf_scene), found));
  EXPECT_EQ(counter.count(), 0);
  EXPECT_EQ(detector.workspace_used(), detector.workspace_bytes());
}

// The cap on the model arcs per scene arc (search_arcs_per_leaf): the search
// keeps the best ranked of what its leaves hold, and what closes the
// object's circuits is among them. Against the ground truth (graf) and the
// uncapped search's own pose (box): found at the same place, with at least
// 3/4 of the support, from fewer arcs; the correspondences that agree with
// graf's ground truth keep at least 3/5 of their number (the cap halves
// the others: 1365 -> 662 on the perf index's graf3 at 20 a leaf). The
// default keeps every arc.
TEST(DetectOptions, ArcCapKeepsTheCircuitsThatFindTheObjects) {
  const Fixture& f = fixture();
  const ModelIndex& index = f.built.index;
  const Limits limits = limits_for(f.box_scene, f.graf_scene);
  DetectOptions all = DetectOptions::from(index);
  EXPECT_EQ(all.search_arcs_per_leaf, DetectOptions::kDefaultSearchArcsPerLeaf);
  EXPECT_EQ(all.search_arcs_per_leaf, 0);
  DetectOptions capped = DetectOptions::from(index);
  capped.search_arcs_per_leaf = 10;  // half of what a leaf holds within the radius
  Detector uncapped_detector(index, limits, all), capped_detector(index, limits, capped);
  ASSERT_TRUE(uncapped_detector.status()) << uncapped_detector.status().message();
  ASSERT_TRUE(capped_detector.status()) << capped_detector.status().message();
  const Homography truth = test::graf_truth();
  // Correspondences whose three model vertices land within 3 px of their
  // scene vertices under the ground truth.
  auto agreeing = [&](const Detector& d) {
    int n = 0;
    const ConstSpan<Keypoint> scene = d.last_keypoints();
    for (const KeygraphMatch& m : d.last_matches()) {
      if (m.model_id != 1) continue;
      bool all_close = true;
      for (int i = 0; i < 3; ++i) {
        const Point2f g = kg::apply(truth, index.keypoints()[m.model_vertices[i]]);
        const Keypoint& k = scene[static_cast<std::size_t>(m.scene_vertices[i])];
        all_close = all_close && std::hypot(g.x - k.x, g.y - k.y) < 3.f;
      }
      n += all_close ? 1 : 0;
    }
    return n;
  };
  for (const cv::Mat* scene : {&f.graf_scene, &f.box_scene}) {
    const bool graf = scene == &f.graf_scene;
    DetectionList a, b;
    ASSERT_TRUE(uncapped_detector.detect(test::view(*scene), a));
    ASSERT_TRUE(capped_detector.detect(test::view(*scene), b));
    ASSERT_EQ(a.size(), 1u);
    ASSERT_EQ(b.size(), 1u);
    ASSERT_EQ(b[0].model_id, graf ? 1 : 0);
    const long long arcs_all = uncapped_detector.stats().arc_matches;
    const long long arcs_capped = capped_detector.stats().arc_matches;
    std::printf("%s: arcs %lld -> %lld, correspondences %d -> %d, inliers %d -> %d\n",
                graf ? "graf3" : "box_in_scene", arcs_all, arcs_capped,
                uncapped_detector.stats().correspondences, capped_detector.stats().correspondences,
                a[0].inliers, b[0].inliers);
    // Each query keeps at most 10 arcs a leaf of the 30 or so it finds.
    EXPECT_LT(arcs_capped, arcs_all * 3 / 4);
    EXPECT_GE(4 * b[0].inliers, 3 * a[0].inliers);
    const ModelInfo model = index.model(b[0].model_id);
    if (graf) {
      EXPECT_LT(test::max_corner_error(b[0], truth, model), 5.0);
      const int right_all = agreeing(uncapped_detector), right_capped = agreeing(capped_detector);
      std::printf("graf3: correspondences agreeing with the truth %d -> %d\n", right_all,
                  right_capped);
      EXPECT_GT(right_all, 20);
      EXPECT_GE(5 * right_capped, 3 * right_all);
    } else {
      EXPECT_LT(test::max_corner_error(b[0], a[0].homography, model), 3.0);
    }
  }
  // Out of range: more than a leaf holds, or negative.
  capped.search_arcs_per_leaf = kLeafSize + 1;
  EXPECT_FALSE(capped_detector.set_options(capped));
  capped.search_arcs_per_leaf = -1;
  EXPECT_FALSE(capped_detector.set_options(capped));
}

// ransac_barren_draws: a model's RANSAC attempt stops once that many draws
// found nothing an instance could be made of. On the two-model index the
// absent model's attempt (graf in box_in_scene, the box in graf3) drew to
// the cap or through its whole pool; stopped early, the frame takes fewer
// RANSAC iterations and finds the same object at the same place (the found
// model's own attempt needs a few draws and is untouched).
TEST(DetectOptions, BarrenDrawsStopAbsentModelsEarly) {
  const Fixture& f = fixture();
  const ModelIndex& index = f.built.index;
  const Limits limits = limits_for(f.box_scene, f.graf_scene);
  DetectOptions full = DetectOptions::from(index);
  EXPECT_EQ(full.ransac_barren_draws, DetectOptions::kDefaultRansacBarrenDraws);
  EXPECT_EQ(full.ransac_barren_draws, 2000);
  full.ransac_barren_draws = 0;  // to the cap
  DetectOptions barren = full;
  barren.ransac_barren_draws = 100;
  Detector full_detector(index, limits, full), barren_detector(index, limits, barren);
  ASSERT_TRUE(full_detector.status()) << full_detector.status().message();
  ASSERT_TRUE(barren_detector.status()) << barren_detector.status().message();
  for (const cv::Mat* scene : {&f.box_scene, &f.graf_scene}) {
    const bool graf = scene == &f.graf_scene;
    DetectionList a, b;
    ASSERT_TRUE(full_detector.detect(test::view(*scene), a));
    ASSERT_TRUE(barren_detector.detect(test::view(*scene), b));
    ASSERT_EQ(a.size(), 1u);
    ASSERT_EQ(b.size(), 1u);
    ASSERT_EQ(b[0].model_id, graf ? 1 : 0);
    const int all = full_detector.stats().ransac_iterations;
    const int stopped = barren_detector.stats().ransac_iterations;
    std::printf("%s: RANSAC iterations %d -> %d (the found model's %d -> %d)\n",
                graf ? "graf3" : "box_in_scene", all, stopped, a[0].ransac_iterations,
                b[0].ransac_iterations);
    // The absent model's barren attempts stop at 100 draws (box_in_scene
    // 1122 -> 202 iterations, graf3 15002 -> 5202, where one cluster of the
    // absent box has the support and runs to the cap).
    EXPECT_LT(2 * stopped, all);
    EXPECT_EQ(b[0].ransac_iterations, a[0].ransac_iterations);
    EXPECT_EQ(b[0].inliers, a[0].inliers);
    EXPECT_LT(test::max_corner_error(b[0], a[0].homography, index.model(b[0].model_id)), 1.0);
    if (graf) {
      EXPECT_LT(test::max_corner_error(b[0], test::graf_truth(), index.model(1)), 5.0);
    }
  }
  // By name; negative counts are refused.
  DetectOptions o;
  EXPECT_TRUE(set_detect_option(o, "ransac_barren_draws", "2000"));
  EXPECT_EQ(o.ransac_barren_draws, 2000);
  barren.ransac_barren_draws = -1;
  EXPECT_FALSE(barren_detector.set_options(barren));
}

TEST(DetectOptions, AlignmentOnlyForWhatCanBeAccepted) {
  // align_coarse_min_ncc: a false cluster's appearance alignment stops
  // after the coarse level, and a cluster on an instance already found is
  // not aligned, while the objects found keep their poses bit for bit.
  const Fixture& f = fixture();
  const ModelIndex& index = f.built.index;
  const Limits limits = limits_for(f.box_scene, f.graf_scene);
  DetectOptions stopping = DetectOptions::from(index);
  EXPECT_EQ(stopping.align_coarse_min_ncc, DetectOptions::kDefaultAlignCoarseMinNcc);
  EXPECT_EQ(stopping.align_coarse_min_ncc, 0.45);
  DetectOptions every = stopping;
  EXPECT_EQ(stopping.align_min_ncc, DetectOptions::kDefaultAlignMinNcc);
  EXPECT_EQ(stopping.align_min_ncc, 0.3);
  every.align_min_ncc = -1.0;  // every cluster aligned in full, as before
  every.align_coarse_min_ncc = -1.0;
  DetectOptions two_threads = stopping;
  Limits two = limits;
  two.threads = 2;
  Detector every_detector(index, limits, every), stopping_detector(index, limits, stopping),
      threaded_detector(index, two, two_threads);
  ASSERT_TRUE(every_detector.status()) << every_detector.status().message();
  ASSERT_TRUE(stopping_detector.status()) << stopping_detector.status().message();
  ASSERT_TRUE(threaded_detector.status()) << threaded_detector.status().message();
  int saved = 0;
  for (const cv::Mat* scene : {&f.box_scene, &f.graf_scene}) {
    const bool graf = scene == &f.graf_scene;
    DetectionList a, b, c;
    ASSERT_TRUE(every_detector.detect(test::view(*scene), a));
    ASSERT_TRUE(stopping_detector.detect(test::view(*scene), b));
    ASSERT_TRUE(threaded_detector.detect(test::view(*scene), c));
    const DetectStats& sa = every_detector.stats();
    const DetectStats& sb = stopping_detector.stats();
    std::printf("%s: alignments %d (%d abandoned) -> %d (%d abandoned)\n",
                graf ? "graf3" : "box_in_scene", sa.alignments, sa.alignments_abandoned,
                sb.alignments, sb.alignments_abandoned);
    ASSERT_EQ(a.size(), 1u);
    ASSERT_EQ(b.size(), 1u);
    ASSERT_EQ(c.size(), 1u);
    EXPECT_EQ(b[0].model_id, graf ? 1 : 0);
    EXPECT_EQ(b[0].model_id, a[0].model_id);
    EXPECT_EQ(b[0].homography, a[0].homography);
    EXPECT_EQ(b[0].appearance, a[0].appearance);
    EXPECT_EQ(b[0].inliers, a[0].inliers);
    EXPECT_EQ(c[0].homography, b[0].homography);
    EXPECT_GT(b[0].appearance, 0.8);
    EXPECT_EQ(sa.alignments_abandoned, 0);
    // The same counts whatever the thread count.
    EXPECT_EQ(threaded_detector.stats().alignments, sb.alignments);
    EXPECT_EQ(threaded_detector.stats().alignments_abandoned, sb.alignments_abandoned);
    if (graf) {
      EXPECT_LT(test::max_corner_error(b[0], test::graf_truth(), index.model(1)), 5.0);
      EXPECT_GE(sb.alignments_abandoned, 1);  // a false cluster
    }
    // Every alignment left runs in full but the abandoned ones, and the
    // found object's is one of them.
    EXPECT_GE(sb.alignments - sb.alignments_abandoned, 1);
    EXPECT_LE(sb.alignments, sa.alignments);
    saved += (sa.alignments - sb.alignments) + sb.alignments_abandoned;
  }
  EXPECT_GT(saved, 0);
  // By name, in [-1, 1].
  DetectOptions o;
  EXPECT_TRUE(set_detect_option(o, "align_coarse_min_ncc", "0.6"));
  EXPECT_EQ(o.align_coarse_min_ncc, 0.6);
  EXPECT_TRUE(set_detect_option(o, "align_coarse_min_ncc", "-1"));
  EXPECT_FALSE(set_detect_option(o, "align_coarse_min_ncc", "1.5"));
  EXPECT_FALSE(set_detect_option(o, "align_coarse_min_ncc", "x"));
  EXPECT_TRUE(set_detect_option(o, "align_min_ncc", "0.2"));
  EXPECT_EQ(o.align_min_ncc, 0.2);
  EXPECT_FALSE(set_detect_option(o, "align_min_ncc", "-2"));
  stopping.align_coarse_min_ncc = 2.0;
  EXPECT_FALSE(stopping_detector.set_options(stopping));
  stopping.align_coarse_min_ncc = 0.45;
  stopping.align_min_ncc = -1.5;
  EXPECT_FALSE(stopping_detector.set_options(stopping));
}

TEST(DetectOptions, NoAlignmentForAClusterOnAnInstanceFound) {
  // graf1 (the whole image) in graf3: after graf is found, RANSAC's next
  // attempts find clusters on the same instance (repeats, rejected), which
  // correlate too well to be abandoned after the coarse level; with
  // align_coarse_min_ncc on they are not aligned at all.
  static const test::InMemoryIndex built = [] {
    test::InMemoryIndex x;
    EXPECT_TRUE(test::build_in_memory({{"graf1", test::load_gray(test::opencv_data("graf1.png"))}},
                                      Params{}, x));
    return x;
  }();
  const ModelIndex& index = built.index;
  const Fixture& f = fixture();
  const Limits limits = Limits{}.for_frame(f.graf_scene.cols, f.graf_scene.rows);
  DetectOptions stopping = DetectOptions::from(index);
  DetectOptions every = stopping;
  every.align_min_ncc = -1.0;
  every.align_coarse_min_ncc = -1.0;
  Detector every_detector(index, limits, every), stopping_detector(index, limits, stopping);
  ASSERT_TRUE(every_detector.status()) << every_detector.status().message();
  ASSERT_TRUE(stopping_detector.status()) << stopping_detector.status().message();
  DetectionList a, b;
  ASSERT_TRUE(every_detector.detect(test::view(f.graf_scene), a));
  ASSERT_TRUE(stopping_detector.detect(test::view(f.graf_scene), b));
  const DetectStats& sa = every_detector.stats();
  const DetectStats& sb = stopping_detector.stats();
  std::printf("graf1 in graf3: alignments %d (%d abandoned) -> %d (%d abandoned)\n", sa.alignments,
              sa.alignments_abandoned, sb.alignments, sb.alignments_abandoned);
  ASSERT_EQ(a.size(), 1u);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(b[0].homography, a[0].homography);
  EXPECT_EQ(b[0].appearance, a[0].appearance);
  EXPECT_GT(b[0].appearance, 0.8);
  EXPECT_GE(sa.alignments, 2);  // the instance and its repeats
  EXPECT_EQ(sb.alignments, 1);  // the instance alone
  EXPECT_EQ(sb.alignments_abandoned, 0);
}

TEST(DetectOptions, SetByName) {
  DetectOptions o;
  EXPECT_TRUE(set_detect_option(o, "ransac.seed", "7"));
  EXPECT_EQ(o.ransac.seed, 7u);
  EXPECT_TRUE(set_detect_option(o, "descriptor.max_search_leaves", "0"));
  EXPECT_EQ(o.max_search_leaves, 0);
  EXPECT_TRUE(set_detect_option(o, "min_confidence", "0.5"));
  EXPECT_EQ(o.min_confidence, 0.5);
  EXPECT_TRUE(set_detect_option(o, "ransac.min_triangle_correlation", "0"));
  EXPECT_EQ(o.ransac.min_triangle_correlation, 0.f);
  EXPECT_TRUE(set_detect_option(o, "search_arcs_per_leaf", "12"));
  EXPECT_EQ(o.search_arcs_per_leaf, 12);
  EXPECT_FALSE(set_detect_option(o, "search_arcs_per_leaf", "1.5"));

  Status s = set_detect_option(o, "descriptor.blur_sigma", "2");
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("fixed by the index"), std::string::npos) << s.message();
  s = set_detect_option(o, "no.such", "1");
  EXPECT_NE(s.message().find("unknown option"), std::string::npos) << s.message();
  EXPECT_FALSE(set_detect_option(o, "ransac.seed", "x"));
  EXPECT_FALSE(set_detect_option(o, "min_confidence", ""));
  EXPECT_EQ(o.ransac.seed, 7u);  // unchanged by the failures

  const std::vector<std::string> names = detect_option_names();
  EXPECT_NE(std::find(names.begin(), names.end(), "ransac.seed"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "min_confidence"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "search_arcs_per_leaf"), names.end());
  EXPECT_EQ(std::find(names.begin(), names.end(), "views.max_tilt"), names.end());
}

// The vector code computes what the portable code computes: the same
// detections, bit for bit, at every SIMD level (keygraph/simd.h).
TEST(SimdLevels, DetectionsIdenticalAtEveryLevel) {
  const Fixture& f = fixture();
  const ModelIndex& index = f.built.index;
  const auto detect_at = [&](SimdLevel level) {
    const test::SimdScope scope(level);
    Detector detector(index, limits_for(f.box_scene, f.graf_scene));
    DetectionList found;
    EXPECT_TRUE(detector.detect(test::view(f.box_scene), found));
    EXPECT_EQ(found.size(), 1u);
    return found.empty() ? Homography{} : found[0].homography;
  };
  const Homography best = detect_at(best_simd_level());
  std::printf("best level: %s\n", simd_level_name(best_simd_level()));
  EXPECT_EQ(detect_at(SimdLevel::kScalar), best);
  EXPECT_EQ(detect_at(SimdLevel::kBaseline), best);
  // Clamped to what the CPU and build have.
  {
    const test::SimdScope scope(SimdLevel::kAvx2);
    EXPECT_EQ(simd_level(), best_simd_level());
  }
}

TEST(Presets, NamedConfigurations) {
  Params p;
  ASSERT_TRUE(preset_params("frontal", p));
  EXPECT_EQ(p.views.max_tilt, 0.f);
  EXPECT_EQ(p.graph.complete_circuits, 0);
  EXPECT_EQ(p.descriptor.max_search_leaves, 20);
  ASSERT_TRUE(preset_params("angled", p));
  EXPECT_EQ(p.views.max_tilt, 60.f);
  EXPECT_EQ(p.views.tilt_levels, 2);
  ASSERT_TRUE(preset_params("defaults", p));
  EXPECT_EQ(p.views.max_tilt, Params{}.views.max_tilt);
  EXPECT_EQ(preset_params("sideways", p).code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace kg
