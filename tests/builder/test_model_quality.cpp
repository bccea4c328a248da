// The model quality report of keygraph build (builder/model_quality.h, rated by
// cli/device/quality_report.h) on real models: a flat or tiny model is
// warned about, two signs that differ only by an arrow's direction are
// reported as look-alikes exactly when the real detector finds one in the
// other's scene, distinct signs are not, and the report survives the index.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "builder/desktop_detect.h"
#include "builder/in_memory_index.h"
#include "builder/index_writer.h"
#include "builder/model_builder.h"
#include "builder/model_quality.h"
#include "cli/device/quality_report.h"
#include "eval/synth/sign_catalogue.h"
#include "eval/synth/sign_pictograms.h"
#include "keygraph/model_index.h"
#include "keygraph/param_text.h"
#include "support/test_data.h"

namespace kg {
namespace {

// Models, their report, and the index holding both (64-byte aligned).
struct Built {
  std::vector<BuiltModel> models;
  QualityReport quality;
  std::unique_ptr<std::uint8_t[]> storage;
  ModelIndex index;
};

void build_all(const std::vector<std::string>& names, const std::vector<cv::Mat>& grays, Built& out,
               const Params& params = Params{}) {
  out.models.resize(grays.size());
  for (std::size_t i = 0; i < grays.size(); ++i) {
    const Status s = build_model(grays[i], names[i], params, out.models[i]);
    ASSERT_TRUE(s) << s.message();
  }
  Status s = measure_quality(out.models, grays, params, QualityOptions{}, out.quality);
  ASSERT_TRUE(s) << s.message();
  std::vector<std::uint8_t> bytes;
  s = serialize_index(out.models, params, bytes, &out.quality);
  ASSERT_TRUE(s) << s.message();
  s = view_aligned_copy(bytes, out.storage, out.index);
  ASSERT_TRUE(s) << s.message();
  ASSERT_TRUE(out.index.has_quality());
}

bool has_warning(const cli::ModelRating& r, const std::string& needle) {
  return std::any_of(r.warnings.begin(), r.warnings.end(),
                     [&](const std::string& w) { return w.find(needle) != std::string::npos; });
}

cv::Mat gray_of(const cv::Mat& bgr) {
  cv::Mat gray;
  cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
  return gray;
}

// A plain rectangle: a dark frame on white, nothing inside.
cv::Mat plain_rectangle() {
  cv::Mat image(160, 240, CV_8UC1, cv::Scalar(255));
  cv::rectangle(image, cv::Rect(20, 20, 200, 120), cv::Scalar(30), 6);
  return image;
}

// A sign of two lines of text and an arrow of `arrow` pixels: `right`
// chooses the arrow's direction, nothing else differs.
cv::Mat arrow_sign(bool right, int arrow) {
  const cv::Scalar green(40, 140, 20), white(255, 255, 255);
  cv::Mat image(200, 360, CV_8UC3, green);  // like exit signs
  cv::putText(image, "FIRE", cv::Point(20, 85), cv::FONT_HERSHEY_SIMPLEX, 2.0, white, 5,
              cv::LINE_AA);
  cv::putText(image, "EXIT", cv::Point(20, 170), cv::FONT_HERSHEY_SIMPLEX, 2.0, white, 5,
              cv::LINE_AA);
  draw_pictogram(image, right ? Pictogram::kArrowRight : Pictogram::kArrowLeft,
                 cv::Rect(340 - arrow, 100 - arrow / 2, arrow, arrow), white, green);
  return gray_of(image);
}

// Whether the detector, with `index`, finds model `detected` in the
// look-alike scene of `shown`: the check done again here, independently.
bool detects_in_scene(const ModelIndex& index, const cv::Mat& shown, int detected) {
  cv::Point2f outline[4];
  const cv::Mat scene = render_quality_scene(shown, QualityOptions{}.scene_long_edge, outline);
  DesktopDetector detector(index);
  DetectionList found;
  EXPECT_TRUE(detector.detect(scene, found));
  for (const Detection& d : found)
    if (d.model_id == detected) return true;
  return false;
}

bool reported(const ModelIndex& index, std::uint32_t shown, std::uint32_t detected) {
  for (std::uint32_t i = 0; i < index.look_alike_count(); ++i) {
    const LookAlike p = index.look_alike(i);
    if (p.shown == shown && p.detected == detected) return true;
  }
  return false;
}

TEST(ModelQuality, FlatAndTinyModelsAreWarned) {
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  ASSERT_FALSE(box.empty()) << "box.png missing (install opencv-doc)";
  Built b;
  build_all({"box", "rectangle", "tiny"},
            {box, plain_rectangle(), box(cv::Rect(120, 60, 40, 30)).clone()}, b);
  // The textured model is sound: found at a modest size, in its scene.
  const cli::ModelRating good = cli::rate_model(b.index, 0);
  EXPECT_GE(good.stars, 4) << (good.warnings.empty() ? "" : good.warnings[0]);
  EXPECT_GT(b.index.model_quality(0).smallest_size, 0.f);
  EXPECT_LT(b.index.model_quality(0).smallest_size, 324.f);  // below its own size
  EXPECT_TRUE(b.index.model_quality(0).found_in_scene);
  // The rectangle and the tiny crop cannot be found at any size.
  for (int m : {1, 2}) {
    SCOPED_TRACE(b.models[static_cast<std::size_t>(m)].name);
    const ModelQuality q = b.index.model_quality(m);
    EXPECT_EQ(q.smallest_size, 0.f);
    const cli::ModelRating r = cli::rate_model(b.index, m);
    EXPECT_EQ(r.stars, 0);
    EXPECT_STREQ(r.grade, "weak");
    EXPECT_TRUE(has_warning(r, "too few keypoints or keygraphs to be found at any size"));
  }
  // Its full-size view says why: few keypoints and keygraphs.
  const ViewQuality flat = b.index.view_quality(b.index.model_quality(1).view_begin);
  EXPECT_LT(flat.keypoints, 24u);
  EXPECT_LT(flat.keygraphs, 100u);
}

// Without views (the paper's model) there is one view, the model image:
// its size is no smallest size, and the rating says so instead of warning
// that the model is only found when large.
TEST(ModelQuality, WithoutViewsTheSmallestSizeIsNotMeasured) {
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  ASSERT_FALSE(box.empty()) << "box.png missing (install opencv-doc)";
  Params params;
  params.views.min_size = 0.f;
  Built b;
  build_all({"box"}, {box}, b, params);
  EXPECT_EQ(b.index.model_quality(0).view_count, 1u);
  const cli::ModelRating r = cli::rate_model(b.index, 0);
  EXPECT_TRUE(has_warning(r, "smallest size not measured"));
  EXPECT_FALSE(has_warning(r, "only be found when large"));
  EXPECT_EQ(r.stars, 5);
}

// Shared arcs of models with tilted views (here 277 k and 460 k arcs) are
// estimated from kSharedSample evenly spaced arcs: a copy of a model still
// shares every arc, and an unrelated model shares well under the half that
// warns of low distinctiveness (a graf crop against box: measured 4 %).
TEST(ModelQuality, SharedArcsOfLargeModelsAreEstimated) {
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  const cv::Mat graf = test::load_gray(test::opencv_data("graf1.png"));
  ASSERT_FALSE(box.empty()) << "box.png missing (install opencv-doc)";
  ASSERT_FALSE(graf.empty()) << "graf1.png missing (install opencv-doc)";
  Params params;
  params.views.max_tilt = 60.f;
  params.views.tilt_levels = 1;
  const std::vector<cv::Mat> grays = {box, box.clone(), graf(cv::Rect(200, 150, 300, 300)).clone()};
  std::vector<BuiltModel> models(grays.size());
  const char* const names[] = {"box", "box copy", "graf crop"};
  for (std::size_t i = 0; i < grays.size(); ++i)
    ASSERT_TRUE(build_model(grays[i], names[i], params, models[i]));
  ASSERT_GT(models[0].arcs.size(), 4u * kSharedSample)
      << "the sampled path needs more arcs than searched";
  QualityOptions options;
  options.look_alikes = false;
  QualityReport quality;
  ASSERT_TRUE(measure_quality(models, grays, params, options, quality));
  ASSERT_EQ(quality.models.size(), 3u);
  EXPECT_EQ(quality.models[0].shared_arcs, models[0].arcs.size()) << "a copy shares every arc";
  EXPECT_EQ(quality.models[1].shared_arcs, models[1].arcs.size());
  EXPECT_GT(quality.models[2].shared_arcs, 0u);
  EXPECT_LT(2 * quality.models[2].shared_arcs, models[2].arcs.size());
}

// Signs that differ only by the arrow's direction, and a distinct sign:
// the report lists a pair exactly when the detector, run again here, finds
// one model in the other's scene; the distinct pair is never listed. What
// the detector does (measured, not assumed): with a large arrow (100 px on
// a 360 px sign) the pose verification tells the two apart; with a small
// one (35 px) the shared text decides and one is found in the other's
// scene.
TEST(ModelQuality, ArrowDirectionLookAlikes) {
  const SignImage distinct = render_sign(33, 1);  // room-101: text only
  ASSERT_EQ(distinct.name, "room-101");
  // Without appearances (views.appearance_size 0) only keypoints tell the
  // two arrows apart; with them (the default) the aligned images do.
  for (const bool appearance_check : {false, true}) {
    Params params;
    // Format 6.5's defaults (arcs between every pair in range, 10 leaves),
    // where the measured look-alike below exists: with the near-neighbour
    // arcs and 8 leaves of 6.6 the small arrows are not confused even
    // without appearances, and the report has no pair to list.
    params.graph.max_neighbour_rank = 0;
    params.descriptor.max_search_leaves = 10;
    // And without the fine Hessian levels (issue 38), with which the small
    // arrows are told apart too.
    params.keypoints.hessian_fine_levels = 0;
    if (!appearance_check) params.views.appearance_size = 0;
    for (const int arrow : {100, 35}) {
      SCOPED_TRACE("arrow " + std::to_string(arrow) + " px, appearance check " +
                   (appearance_check ? "on" : "off"));
      const std::vector<cv::Mat> grays = {arrow_sign(true, arrow), arrow_sign(false, arrow),
                                          gray_of(distinct.image)};
      Built b;
      build_all({"exit-arrow-right", "exit-arrow-left", "room-101"}, grays, b, params);
      for (std::uint32_t shown = 0; shown < 3; ++shown) {
        for (std::uint32_t detected = 0; detected < 3; ++detected) {
          if (shown == detected) continue;
          SCOPED_TRACE(b.models[shown].name + " -> " + b.models[detected].name);
          EXPECT_EQ(reported(b.index, shown, detected),
                    detects_in_scene(b.index, grays[shown], static_cast<int>(detected)));
        }
      }
      // Measured on this machine: with the small arrow and keypoints alone,
      // exit-arrow-left is found in exit-arrow-right's scene (instead of
      // exit-arrow-right itself), not the other way round; with the
      // appearance that detection is gone.
      const bool look_alike = arrow == 35 && !appearance_check;
      EXPECT_EQ(reported(b.index, 0, 1) || reported(b.index, 1, 0), look_alike);
      for (std::uint32_t m : {0u, 1u}) {
        EXPECT_FALSE(reported(b.index, m, 2));
        EXPECT_FALSE(reported(b.index, 2, m));
        const cli::ModelRating r = cli::rate_model(b.index, static_cast<int>(m));
        EXPECT_EQ(has_warning(r, "look-alike of " + b.models[1 - m].name), look_alike);
      }
      if (arrow == 100) {
        EXPECT_TRUE(b.index.model_quality(0).found_in_scene);
        EXPECT_TRUE(b.index.model_quality(1).found_in_scene);
      }
      EXPECT_FALSE(has_warning(cli::rate_model(b.index, 2), "look-alike"));
    }
  }
}

// The report is measured on several threads (QualityOptions::threads): any
// count gives the same report, look-alike pairs in the same order, so the
// index is the same file. Copies make look-alikes of several models.
TEST(ModelQuality, SameReportOnAnyThreadCount) {
  // Frontal views, as measured: with the tilted views and completion this
  // case makes look-alike detections in only two models' scenes, and it
  // needs several (tilted views on several threads: cli_quality.sh).
  Params params = frontal_params();
  params.views.appearance_size = 0;          // keypoints alone: the small arrows are look-alikes
  params.keypoints.hessian_fine_levels = 0;  // with the fine levels (issue 38) fewer are
  const cv::Mat right = arrow_sign(true, 35), room = gray_of(render_sign(33, 1).image);
  const std::vector<cv::Mat> grays = {right, arrow_sign(false, 35), room, right.clone(),
                                      room.clone()};
  std::vector<BuiltModel> models(grays.size());
  const char* const names[] = {"right", "left", "room", "right copy", "room copy"};
  for (std::size_t i = 0; i < grays.size(); ++i)
    ASSERT_TRUE(build_model(grays[i], names[i], params, models[i]));
  std::vector<std::uint8_t> first;
  for (const int threads : {1, 2, 4}) {
    SCOPED_TRACE(std::to_string(threads) + " threads");
    QualityOptions options;
    options.threads = threads;
    QualityReport quality;
    ASSERT_TRUE(measure_quality(models, grays, params, options, quality));
    std::set<std::uint32_t> shown;
    for (const LookAlike& pair : quality.look_alikes) shown.insert(pair.shown);
    EXPECT_GE(shown.size(), 3u) << "the case needs look-alikes in several models' scenes";
    EXPECT_TRUE(std::is_sorted(quality.look_alikes.begin(), quality.look_alikes.end(),
                               [](const LookAlike& a, const LookAlike& b) {
                                 return a.shown != b.shown ? a.shown < b.shown
                                                           : a.detected < b.detected;
                               }))
        << "pairs in model order";
    std::vector<std::uint8_t> bytes;
    ASSERT_TRUE(serialize_index(models, params, bytes, &quality));
    if (first.empty()) {
      first = bytes;
    } else {
      EXPECT_TRUE(bytes == first) << "the index differs from the one-thread build";
    }
  }
}

// The catalogue's exit-right and exit-left (arrow direction and layout
// mirrored) in the style of the sign benchmark's seed 1.
TEST(ModelQuality, CatalogueExitSignsAsTheDetectorSeesThem) {
  const SignImage exit_right = render_sign(0, 1), exit_left = render_sign(1, 1);
  ASSERT_EQ(exit_right.name, "exit-right");
  ASSERT_EQ(exit_left.name, "exit-left");
  const std::vector<cv::Mat> grays = {gray_of(exit_right.image), gray_of(exit_left.image)};
  Built b;
  build_all({exit_right.name, exit_left.name}, grays, b);
  EXPECT_EQ(reported(b.index, 0, 1), detects_in_scene(b.index, grays[0], 1));
  EXPECT_EQ(reported(b.index, 1, 0), detects_in_scene(b.index, grays[1], 0));
  EXPECT_TRUE(b.index.model_quality(0).found_in_scene);
  EXPECT_TRUE(b.index.model_quality(1).found_in_scene);
}

}  // namespace
}  // namespace kg
