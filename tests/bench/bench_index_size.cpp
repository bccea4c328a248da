// What a frame costs as the index grows, and what the search still finds:
// detection of box in box_in_scene.png and of the graf crop in graf3.png
// (native sizes) with an index of 1 (box alone), 2 (box and the graf crop),
// 10, 50 and 200 models, the others 240x240 tiles of unrelated opencv-doc
// photos (tests/support/opencv_scenes.h; the same models as the recall test,
// tests/core/test_search_recall.cpp). Counters per frame: the
// index's arcs, model arcs the scene arcs matched, keygraph
// correspondences, the target's inliers, and whether it was found. The
// Exact variants search the tree exactly (descriptor.max_search_leaves 0)
// with room for every match (a 128 MB arc pool): what the approximate
// search's fixed cost gives up.
//
//   cmake --preset bench && cmake --build --preset bench --target bench_index_size
//   build/bench/tests/bench/bench_index_size --benchmark_repetitions=3
//     --benchmark_report_aggregates_only=true
//
// Figures: docs/RESULTS.md, "Index size and recall".
#include <benchmark/benchmark.h>

#include <algorithm>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "builder/desktop_detect.h"
#include "builder/model_builder.h"
#include "support/opencv_scenes.h"

namespace kg {
namespace {

constexpr int kMostModels = 200;

struct Models {
  BuiltModel box, graf;
  std::vector<BuiltModel> others;  // distractors, built when first needed
  cv::Mat box_scene, graf_scene;
  bool ok = false;
};

Models& models() {
  static Models m;
  static bool loaded = false;
  if (loaded) return m;
  loaded = true;
  const cv::Mat box = test::load_gray(test::opencv_data("box.png"));
  m.box_scene = test::load_gray(test::opencv_data("box_in_scene.png"));
  m.graf_scene = test::load_gray(test::opencv_data("graf3.png"));
  if (box.empty() || m.box_scene.empty() || m.graf_scene.empty()) return m;
  if (!build_model(box, "box", Params{}, m.box).is_ok()) return m;
  if (!build_model(test::graf_crop(), "graf-crop", Params{}, m.graf).is_ok()) return m;
  m.ok = true;
  return m;
}

// The index of `count` models, built once (exact: searched exactly).
const test::InMemoryIndex* index_of(int count, bool exact) {
  static std::map<std::pair<int, bool>, std::unique_ptr<test::InMemoryIndex>> cache;
  auto& slot = cache[{count, exact}];
  if (slot) return slot.get();
  Models& m = models();
  if (!m.ok) return nullptr;
  const auto others = static_cast<std::size_t>(std::max(0, count - 2));
  if (m.others.size() < others) m.others = test::distractor_models(kMostModels - 2);
  if (m.others.size() < others) return nullptr;
  std::vector<BuiltModel> list{m.box};
  if (count > 1) list.push_back(m.graf);
  for (int i = 2; i < count; ++i) list.push_back(m.others[static_cast<std::size_t>(i - 2)]);
  Params params;
  if (exact) params.descriptor.max_search_leaves = 0;
  slot = std::make_unique<test::InMemoryIndex>();
  if (!test::view_in_memory(list, params, *slot).is_ok()) slot.reset();
  return slot.get();
}

void detect_target(benchmark::State& state, bool graf, bool exact) {
  const int count = static_cast<int>(state.range(0));
  if (graf && count < 2) {
    state.SkipWithError("the graf crop is in indexes of 2 or more models");
    return;
  }
  const test::InMemoryIndex* index = index_of(count, exact);
  if (index == nullptr) {
    state.SkipWithError("opencv-doc images missing or a model failed to build");
    return;
  }
  const Models& m = models();
  const cv::Mat& scene = graf ? m.graf_scene : m.box_scene;
  Limits limits = Limits{}.for_frame(scene.cols, scene.rows);
  if (exact) {
    limits.max_arc_matches = 1 << 16;
    limits.max_arc_pool = 1 << 24;
    limits.max_correspondences = 1 << 20;
  }
  DesktopDetector detector(index->index, limits);
  DetectionList found;
  for (auto _ : state) {
    if (Status s = detector.detect(scene, found); !s) {
      state.SkipWithError(s.message().c_str());
      return;
    }
    benchmark::DoNotOptimize(found.size());
  }
  const DetectStats& st = detector.stats();
  int inliers = 0;
  for (const Detection& d : found)
    if (d.model_name == (graf ? "graf-crop" : "box")) inliers = d.inliers;
  state.counters["arcs"] = index->index.arc_count();
  state.counters["MB"] = static_cast<double>(index->bytes) / 1e6;
  state.counters["arc_matches"] = static_cast<double>(st.arc_matches);
  state.counters["pool_full"] = st.truncated_arc_matches ? 1 : 0;
  state.counters["correspondences"] = st.correspondences;
  state.counters["inliers"] = inliers;
  state.counters["found"] = inliers > 0 ? 1 : 0;
}

void BM_BoxInBoxInScene(benchmark::State& state) {
  detect_target(state, false, false);
}
void BM_GrafCropInGraf3(benchmark::State& state) {
  detect_target(state, true, false);
}
void BM_BoxInBoxInSceneExact(benchmark::State& state) {
  detect_target(state, false, true);
}
void BM_GrafCropInGraf3Exact(benchmark::State& state) {
  detect_target(state, true, true);
}
BENCHMARK(BM_BoxInBoxInScene)
    ->Arg(1)
    ->Arg(2)
    ->Arg(10)
    ->Arg(50)
    ->Arg(200)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GrafCropInGraf3)->Arg(2)->Arg(10)->Arg(50)->Arg(200)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BoxInBoxInSceneExact)->Arg(2)->Arg(200)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GrafCropInGraf3Exact)->Arg(2)->Arg(200)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace kg

BENCHMARK_MAIN();
