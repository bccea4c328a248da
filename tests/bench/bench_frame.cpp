// Time per 640x480 frame of keygraph detection with a 10-model index, of
// each stage that can be called alone, and of OpenCV's ORB pipeline (2000
// features, brute-force Hamming 2-NN against each model, Lowe ratio 0.8,
// findHomography RANSAC per model: eval/baselines.h) on the same frames,
// all on one thread. After the benchmarks, a summary gives per frame the
// models each pipeline found and the ratio ORB time / keygraph time.
//
// Models (opencv-doc): box.png, graf1.png cropped 300x300 at (200, 150),
// LinuxLogo.jpg, WindowsLogo.jpg, opencv-logo.png, HappyFish.jpg and
// 300x300 centre crops of starry_night.jpg, baboon.jpg, building.jpg and
// butterfly.jpg, built in-process with the default parameters; and, for
// the paper's one-object setting, an index of box.png alone; and the 10
// models without their appearances (detect_no_appearance/) and searched in
// each frame and in the frame upsampled 2x (keypoints.scene_upsample 3,
// detect_upsampled/), and rebuilt in the frontal configuration (the
// defaults before the 45-degree views: no tilted views, triangle check or
// circuit completion, 20 leaves; detect_frontal/), and the opt-in for
// signs seen at an angle: rebuilt with ASIFT's 60 degrees in 2 levels
// (detect_angled/). Frames:
// box_in_scene.png (holds box), graf3.png (holds the graf crop), aero1.jpg,
// leuvenA.jpg, messi5.jpg and fruits.jpg, resized to 640x480 (INTER_AREA).
//
//   cmake -S . -B build/gbench -DCMAKE_BUILD_TYPE=Release -DKG_BUILD_BENCHMARKS=ON
//   cmake --build build/gbench -j2 --target bench_frame
//   build/gbench/tests/bench/bench_frame --benchmark_repetitions=3
//     --benchmark_report_aggregates_only=true
//
// Figures: docs/RUNTIME.md, "Frame benchmark".
#include <benchmark/benchmark.h>

#include <array>
#include <cstdio>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "builder/image_io.h"
#include "builder/in_memory_index.h"
#include "builder/model_builder.h"
#include "core/description/arc_attributes.h"
#include "core/description/arc_descriptor.h"
#include "core/description/arc_types.h"
#include "core/image/blur.h"
#include "core/keygraphs/delaunay.h"
#include "core/keygraphs/keygraph.h"
#include "core/keypoints/hessian.h"
#include "core/sampling/sampling.h"
#include "core/selection/selection.h"
#include "eval/baselines.h"
#include "keygraph/detector.h"
#include "keygraph/param_text.h"
#include "keygraph/tracker.h"

namespace kg {
namespace {

constexpr int kFrameWidth = 640, kFrameHeight = 480;

struct ModelSource {
  const char* file;
  int crop_x, crop_y;  // top-left of a 300x300 crop; -1: whole image, -2: centre crop
};
constexpr ModelSource kModels[] = {{"box.png", -1, -1},          {"graf1.png", 200, 150},
                                   {"LinuxLogo.jpg", -1, -1},    {"WindowsLogo.jpg", -1, -1},
                                   {"opencv-logo.png", -1, -1},  {"HappyFish.jpg", -1, -1},
                                   {"starry_night.jpg", -2, -2}, {"baboon.jpg", -2, -2},
                                   {"building.jpg", -2, -2},     {"butterfly.jpg", -2, -2}};
constexpr const char* kFrames[] = {"box_in_scene.png", "graf3.png",  "aero1.jpg",
                                   "leuvenA.jpg",      "messi5.jpg", "fruits.jpg"};

std::string stem(const std::string& file) {
  return file.substr(0, file.find('.'));
}

// A frame and the inputs of each stage as the detector computes them.
struct Frame {
  std::string name;
  cv::Mat gray;
  std::vector<Keypoint> keypoints;  // Hessian, strongest first, at most Limits::max_keypoints
  std::vector<Point2f> points;      // after strongest-first sampling
  std::vector<float> scales;
  Delaunay triangulation;
  WorkVector<SceneKeygraph> keygraphs;
  Plane<std::uint8_t> blurred;
  // Scene arcs (half-edges at least graph.min_distance long) with a descriptor.
  std::vector<ArcDescriptor> arcs;
  std::vector<std::array<float, kArcAttributes>> attributes;
  std::vector<char> has_attributes;
};

struct Data {
  std::vector<cv::Mat> models;
  std::vector<std::string> model_names;
  Params params;
  Limits limits;
  InMemoryIndex index;
  InMemoryIndex box_only;  // the paper's setting: one object (box.png)
  // The 10 models without their appearances (views.appearance_size 0): the
  // cost of the photometric refinement is detect/ against this.
  InMemoryIndex no_appearance;
  // The 10 models searched in the frame and in the frame upsampled 2x
  // (keypoints.scene_upsample 3; the model side is the same).
  InMemoryIndex upsampled;
  // The 10 models in the frontal configuration (frontal_params();
  // detect_frontal/): what the defaults cost against it.
  InMemoryIndex frontal;
  // The opt-in for signs seen at an angle (angled_params()): tilted views
  // to 60 degrees in 2 levels, the triangle check, circuit completion, 10
  // leaves; detect_angled/.
  InMemoryIndex angled;
  std::vector<Frame> frames;
};

Data& data() {
  static Data d;
  return d;
}

Status load_models(Data& d) {
  for (const ModelSource& m : kModels) {
    cv::Mat gray;
    if (Status s = load_gray(std::string(KG_OPENCV_DATA_DIR) + "/" + m.file, gray); !s) return s;
    if (m.crop_x != -1) {
      const int x = m.crop_x >= 0 ? m.crop_x : (gray.cols - 300) / 2;
      const int y = m.crop_y >= 0 ? m.crop_y : (gray.rows - 300) / 2;
      gray = gray(cv::Rect(x, y, 300, 300)).clone();
    }
    d.models.push_back(gray);
    d.model_names.push_back(stem(m.file));
  }
  std::vector<BuiltModel> built(d.models.size());
  for (std::size_t i = 0; i < d.models.size(); ++i) {
    if (Status s = build_model(d.models[i], d.model_names[i], d.params, built[i]); !s) return s;
  }
  if (Status s = d.box_only.build({built[0]}, d.params); !s) return s;
  Params without = d.params;
  without.views.appearance_size = 0;
  if (Status s = d.no_appearance.build(built, without); !s) return s;
  Params upsampled = d.params;
  upsampled.keypoints.scene_upsample = 3;
  if (Status s = d.upsampled.build(built, upsampled); !s) return s;
  for (const auto& [params, index] :
       {std::pair{frontal_params(d.params), &d.frontal}, {angled_params(d.params), &d.angled}}) {
    std::vector<BuiltModel> rebuilt(d.models.size());
    for (std::size_t i = 0; i < d.models.size(); ++i) {
      if (Status s = build_model(d.models[i], d.model_names[i], params, rebuilt[i]); !s) return s;
    }
    if (Status s = index->build(rebuilt, params); !s) return s;
  }
  return d.index.build(built, d.params);
}

Status prepare_frame(const Data& d, const char* file, Frame& f) {
  cv::Mat gray;
  if (Status s = load_gray(std::string(KG_OPENCV_DATA_DIR) + "/" + file, gray); !s) return s;
  f.name = stem(file);
  cv::resize(gray, f.gray, cv::Size(kFrameWidth, kFrameHeight), 0, 0, cv::INTER_AREA);
  HessianDetector hessian;
  hessian.detect(view_of(f.gray), d.params.keypoints, d.limits.max_keypoints, f.keypoints);
  SeparatedSampler sampler;
  std::vector<int> selected;
  sampler.sample(f.keypoints.data(), static_cast<int>(f.keypoints.size()),
                 d.params.graph.scene_sample_distance, nullptr, selected);
  if (static_cast<int>(selected.size()) > d.limits.max_scene_keypoints)
    selected.resize(static_cast<std::size_t>(d.limits.max_scene_keypoints));
  for (int i : selected) {
    f.points.push_back(
        {f.keypoints[static_cast<std::size_t>(i)].x, f.keypoints[static_cast<std::size_t>(i)].y});
    f.scales.push_back(f.keypoints[static_cast<std::size_t>(i)].scale);
  }
  f.triangulation.triangulate(f.points.data(), static_cast<int>(f.points.size()));
  scene_keygraphs(f.triangulation, f.points.data(), d.params.graph.structure, f.keygraphs);
  Plane<float> scratch;
  gaussian_blur(view_of(f.gray), d.params.descriptor.blur_sigma, f.blurred, scratch);
  const auto& tri = f.triangulation.triangles();
  std::vector<float> profile;
  for (std::size_t e = 0; e < tri.size(); ++e) {
    const int from = tri[e],
              to = tri[static_cast<std::size_t>(Delaunay::next(static_cast<int>(e)))];
    const Point2f a = f.points[static_cast<std::size_t>(from)],
                  b = f.points[static_cast<std::size_t>(to)];
    ArcDescriptor desc;
    if (chebyshev(a, b) < d.params.graph.min_distance ||
        !arc_descriptor(view_of(f.blurred), a, b, d.params.descriptor, profile, desc))
      continue;
    std::array<float, kArcAttributes> attr{};
    f.has_attributes.push_back(arc_attributes(a, b, f.scales[static_cast<std::size_t>(from)],
                                              f.scales[static_cast<std::size_t>(to)], attr.data()));
    f.arcs.push_back(desc);
    f.attributes.push_back(attr);
  }
  return Status::ok();
}

void set_average(benchmark::State& state, const char* name, double sum) {
  state.counters[name] = benchmark::Counter(sum, benchmark::Counter::kAvgIterations);
}

// ------------------------------------------------------------ whole frame

void detect_with(benchmark::State& state, const Frame* f, const ModelIndex& index) {
  Detector detector(index, data().limits);
  DetectionList found;
  double ms[5] = {0, 0, 0, 0, 0};
  for (auto _ : state) {
    const Status s = detector.detect(view_of(f->gray), found);
    if (!s) {
      state.SkipWithError(s.message().c_str());
      break;
    }
    const DetectStats& st = detector.stats();
    ms[0] += st.ms_keypoints;
    ms[1] += st.ms_graph;
    ms[2] += st.ms_describe;
    ms[3] += st.ms_select;
    ms[4] += st.ms_pose;
    benchmark::DoNotOptimize(found.size());
  }
  set_average(state, "ms_keypoints", ms[0]);
  set_average(state, "ms_graph", ms[1]);
  set_average(state, "ms_describe", ms[2]);
  set_average(state, "ms_select", ms[3]);
  set_average(state, "ms_pose", ms[4]);
  const DetectStats& st = detector.stats();
  state.counters["keypoints"] = st.keypoints;
  state.counters["sampled"] = st.sampled_keypoints;
  state.counters["correspondences"] = st.correspondences;
  state.counters["detections"] = static_cast<double>(found.size());
  if (st.completion_tried > 0) {
    state.counters["completion_tried"] = static_cast<double>(st.completion_tried);
    state.counters["completion_clockwise"] = static_cast<double>(st.completion_clockwise);
    state.counters["completion_plausible"] = static_cast<double>(st.completion_plausible);
    state.counters["completion_closed"] = static_cast<double>(st.completion_closed);
  }
}

void detect_frame(benchmark::State& state, const Frame* f) {
  detect_with(state, f, data().index.index());
}

void detect_no_appearance(benchmark::State& state, const Frame* f) {
  detect_with(state, f, data().no_appearance.index());
}

void detect_frontal(benchmark::State& state, const Frame* f) {
  detect_with(state, f, data().frontal.index());
}

void detect_angled(benchmark::State& state, const Frame* f) {
  detect_with(state, f, data().angled.index());
}

void detect_upsampled(benchmark::State& state, const Frame* f) {
  detect_with(state, f, data().upsampled.index());
}

// The 10-model index with Limits::threads = 2 (the same detections as one
// thread, tests/core/test_threads.cpp): real time is the one to compare.
void detect_threads2(benchmark::State& state, const Frame* f) {
  Limits limits = data().limits;
  limits.threads = 2;
  Detector detector(data().index.index(), limits);
  DetectionList found;
  for (auto _ : state) {
    const Status s = detector.detect(view_of(f->gray), found);
    if (!s) {
      state.SkipWithError(s.message().c_str());
      break;
    }
    benchmark::DoNotOptimize(found.size());
  }
}

// A tracked frame (keygraph/tracker.h): the tracker has found the frame's
// objects once (a full detection, untimed) and then follows them in the
// same frame, as on a camera that does not move; a detect_interval longer
// than any run keeps it from re-detecting. Frames where nothing is found have nothing to
// follow and are skipped.
void tracked_frame(benchmark::State& state, const Frame* f) {
  Detector detector(data().index.index(), data().limits);
  TrackerOptions options;
  options.detect_interval = 1 << 30;
  Tracker tracker(detector, options);
  DetectionList found;
  if (!tracker.process(view_of(f->gray), found) || found.empty()) {
    state.SkipWithError("nothing found to track in this frame");
    return;
  }
  long long tracked = 0;
  for (auto _ : state) {
    const Status s = tracker.process(view_of(f->gray), found);
    if (!s) {
      state.SkipWithError(s.message().c_str());
      break;
    }
    tracked += tracker.stats().detected ? 0 : 1;
    benchmark::DoNotOptimize(found.size());
  }
  state.counters["tracked_fraction"] =
      benchmark::Counter(static_cast<double>(tracked), benchmark::Counter::kAvgIterations);
}

// The same frames against an index of box.png alone (the paper's timing
// experiment detected one object).
void detect_box_only(benchmark::State& state, const Frame* f) {
  detect_with(state, f, data().box_only.index());
}

void orb_pipeline(benchmark::State& state, const Frame* f) {
  BaselineOptions options;
  options.features = BaselineFeatures::kOrb;
  options.estimator = BaselineEstimator::kRansac;
  options.ratio = 0.8f;
  BaselineDetector orb(options);
  orb.set_models(data().models);
  std::vector<BaselineDetection> found;
  double ms[3] = {0, 0, 0};
  for (auto _ : state) {
    orb.detect(f->gray, found);
    ms[0] += orb.stats().ms_features;
    ms[1] += orb.stats().ms_match;
    ms[2] += orb.stats().ms_homography;
    benchmark::DoNotOptimize(found.size());
  }
  set_average(state, "ms_features", ms[0]);
  set_average(state, "ms_match", ms[1]);
  set_average(state, "ms_homography", ms[2]);
  state.counters["keypoints"] = orb.stats().scene_keypoints;
  state.counters["detections"] = static_cast<double>(found.size());
}

// ------------------------------------------------------------ stages alone

void hessian_stage(benchmark::State& state, const Frame* f) {
  HessianDetector hessian;
  std::vector<Keypoint> out;
  for (auto _ : state) {
    hessian.detect(view_of(f->gray), data().params.keypoints, data().limits.max_keypoints, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["keypoints"] = static_cast<double>(out.size());
}

void sampling_stage(benchmark::State& state, const Frame* f) {
  SeparatedSampler sampler;
  std::vector<int> selected;
  for (auto _ : state) {
    sampler.sample(f->keypoints.data(), static_cast<int>(f->keypoints.size()),
                   data().params.graph.scene_sample_distance, nullptr, selected);
    benchmark::DoNotOptimize(selected.data());
  }
  state.counters["sampled"] = static_cast<double>(selected.size());
}

void delaunay_stage(benchmark::State& state, const Frame* f) {
  Delaunay triangulation;
  for (auto _ : state) {
    triangulation.triangulate(f->points.data(), static_cast<int>(f->points.size()));
    benchmark::DoNotOptimize(triangulation.triangles().data());
  }
  state.counters["triangles"] = triangulation.triangle_count();
}

void keygraph_stage(benchmark::State& state, const Frame* f) {
  WorkVector<SceneKeygraph> keygraphs;
  for (auto _ : state) {
    scene_keygraphs(f->triangulation, f->points.data(), data().params.graph.structure, keygraphs);
    benchmark::DoNotOptimize(keygraphs.data());
  }
  state.counters["keygraphs"] = static_cast<double>(keygraphs.size());
}

void blur_stage(benchmark::State& state, const Frame* f) {
  Plane<std::uint8_t> blurred;
  Plane<float> scratch;
  for (auto _ : state) {
    gaussian_blur(view_of(f->gray), data().params.descriptor.blur_sigma, blurred, scratch);
    benchmark::DoNotOptimize(blurred.data());
  }
}

// Every scene arc of the triangulation described once (the selection
// describes each on first use, and reuses the reverse arc's look-up).
void arc_descriptor_stage(benchmark::State& state, const Frame* f) {
  const auto& tri = f->triangulation.triangles();
  std::vector<float> profile;
  int described = 0;
  for (auto _ : state) {
    described = 0;
    for (std::size_t e = 0; e < tri.size(); ++e) {
      const Point2f a = f->points[static_cast<std::size_t>(tri[e])];
      const Point2f b = f->points[static_cast<std::size_t>(
          tri[static_cast<std::size_t>(Delaunay::next(static_cast<int>(e)))])];
      if (chebyshev(a, b) < data().params.graph.min_distance) continue;
      ArcDescriptor d;
      described += arc_descriptor(view_of(f->blurred), a, b, data().params.descriptor, profile, d);
      benchmark::DoNotOptimize(d.data());
    }
  }
  state.counters["arcs"] = described;
}

// One radius query (descriptor and scale attributes) per described scene arc.
void arc_search_stage(benchmark::State& state, const Frame* f) {
  const ArcSearch search(data().index.index());
  std::vector<std::uint32_t> found(static_cast<std::size_t>(data().limits.max_arc_matches));
  long long matches = 0;
  for (auto _ : state) {
    matches = 0;
    for (std::size_t i = 0; i < f->arcs.size(); ++i) {
      matches +=
          search.radius_search(f->arcs[i], f->has_attributes[i] ? f->attributes[i].data() : nullptr,
                               found.data(), static_cast<std::uint32_t>(found.size()));
    }
    benchmark::DoNotOptimize(found.data());
  }
  state.counters["queries"] = static_cast<double>(f->arcs.size());
  state.counters["matches"] = static_cast<double>(matches);
}

// The scene arcs' descriptors (ms_describe, without the blur) and the
// keytuple selection with its look-ups (ms_select), without circuit
// completion.
void selection_stage(benchmark::State& state, const Frame* f) {
  const ArcSearch search(data().index.index());
  const Params& params = data().index.index().params();
  Selector selector;
  selector.reserve(data().limits, data().index.index());
  SceneArcs arcs;
  arcs.reserve(f->gray.cols, f->gray.rows, static_cast<int>(f->points.size()),
               params.descriptor.blur_sigma);
  arcs.blur(ImageView(f->gray.data, f->gray.cols, f->gray.rows,
                      static_cast<std::ptrdiff_t>(f->gray.step)),
            params.descriptor);
  const Structure structure = params.graph.structure;
  const int arcs_per_keygraph = structure == Structure::kArc ? 1 : vertex_count(structure);
  SelectionInput in;
  in.index = &data().index.index();
  in.params = &params;
  in.search = &search;
  in.scene_points = f->points.data();
  in.triangulation = &f->triangulation;
  in.keygraphs = &f->keygraphs;
  in.arcs = &arcs;
  WorkVector<KeygraphMatch> matches;
  matches.reserve(static_cast<std::size_t>(data().limits.max_correspondences));
  DetectStats stats;
  for (auto _ : state) {
    stats = DetectStats{};
    arcs.describe(search, params, f->points.data(), f->scales.data(), f->triangulation,
                  f->keygraphs, arcs_per_keygraph);
    selector.select(in, data().limits, matches, stats);
    benchmark::DoNotOptimize(matches.data());
  }
  state.counters["correspondences"] = static_cast<double>(matches.size());
  state.counters["arc_matches"] = static_cast<double>(stats.arc_matches);
}

// ------------------------------------------------------------ summary

// The console output, keeping the real and CPU time per run name (the
// median when repetitions are aggregated, else the last run).
class SummaryReporter : public benchmark::ConsoleReporter {
 public:
  // Colours only on a terminal (a reporter made here does not read
  // --benchmark_color).
  SummaryReporter() : ConsoleReporter(isatty(fileno(stdout)) ? OO_ColorTabular : OO_Tabular) {}
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& r : runs) {
      if (r.error_occurred) continue;
      const bool median = r.run_type == Run::RT_Aggregate && r.aggregate_name == "median";
      if (r.run_type == Run::RT_Aggregate && !median) continue;
      const std::string name = r.run_name.function_name;
      if (median || !medians_.count(name))
        ms_[name] = {r.GetAdjustedRealTime(), r.GetAdjustedCPUTime()};
      if (median) medians_[name] = true;
    }
  }
  // Real and CPU milliseconds (every benchmark reports in ms), or -1 when
  // not run.
  std::pair<double, double> ms(const std::string& name) const {
    const auto it = ms_.find(name);
    return it == ms_.end() ? std::pair{-1.0, -1.0} : it->second;
  }

 private:
  std::map<std::string, std::pair<double, double>> ms_;
  std::map<std::string, bool> medians_;
};

std::string found_by_keygraph(const Frame& f) {
  Detector detector(data().index.index(), data().limits);
  DetectionList found;
  std::string names;
  if (!detector.detect(view_of(f.gray), found)) return "(error)";
  for (const Detection& d : found) {
    if (!names.empty()) names += ',';
    names += d.model_name;
  }
  return names.empty() ? "-" : names;
}

std::string found_by_orb(const Frame& f) {
  BaselineOptions options;
  options.features = BaselineFeatures::kOrb;
  BaselineDetector orb(options);
  orb.set_models(data().models);
  std::vector<BaselineDetection> found;
  orb.detect(f.gray, found);
  std::string names;
  for (const BaselineDetection& d : found) {
    if (!names.empty()) names += ',';
    names += data().model_names[static_cast<std::size_t>(d.model_id)];
  }
  return names.empty() ? "-" : names;
}

void print_summary(const SummaryReporter& reporter) {
  std::printf("\nSummary: time per frame, real (CPU) ms; medians of repetitions when aggregated\n");
  std::printf("workspace: %zu bytes for Limits{} at %dx%d, %d models, %u model arcs\n",
              Detector::workspace_bytes(data().index.index(), data().limits), kFrameWidth,
              kFrameHeight, data().index.index().model_count(),
              static_cast<unsigned>(data().index.index().arc_count()));
  std::printf("%-14s %18s %18s %14s  %-12s %-12s %18s\n", "frame", "keygraph", "ORB pipeline",
              "ORB/keygraph", "keygraph found", "ORB found", "keygraph, box only");
  std::pair<double, double> kg_total{0, 0}, orb_total{0, 0}, one_total{0, 0};
  bool one_complete = true;
  bool complete = true;
  const auto cell = [](std::pair<double, double> ms) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "%.2f (%.2f)", ms.first, ms.second);
    return std::string(buf);
  };
  for (const Frame& f : data().frames) {
    const auto kg = reporter.ms("detect/" + f.name), orb = reporter.ms("orb_pipeline/" + f.name);
    const auto one = reporter.ms("detect_box_only/" + f.name);
    if (one.first > 0) {
      one_total = {one_total.first + one.first, one_total.second + one.second};
    } else {
      one_complete = false;
    }
    if (kg.first <= 0 || orb.first <= 0) {
      complete = false;
      continue;
    }
    kg_total = {kg_total.first + kg.first, kg_total.second + kg.second};
    orb_total = {orb_total.first + orb.first, orb_total.second + orb.second};
    const std::pair<double, double> ratio{orb.first / kg.first, orb.second / kg.second};
    std::printf("%-14s %18s %18s %14s  %-12s %-12s %18s\n", f.name.c_str(), cell(kg).c_str(),
                cell(orb).c_str(), cell(ratio).c_str(), found_by_keygraph(f).c_str(),
                found_by_orb(f).c_str(), one.first > 0 ? cell(one).c_str() : "-");
  }
  if (kg_total.first > 0 && complete) {
    const std::pair<double, double> ratio{orb_total.first / kg_total.first,
                                          orb_total.second / kg_total.second};
    std::printf("%-14s %18s %18s %14s  %-12s %-12s %18s\n", "all frames", cell(kg_total).c_str(),
                cell(orb_total).c_str(), cell(ratio).c_str(), "", "",
                one_complete ? cell(one_total).c_str() : "-");
    std::printf("ratio ORB pipeline / keygraph over all frames: %.2f real, %.2f CPU\n", ratio.first,
                ratio.second);
    const double n = static_cast<double>(data().frames.size());
    std::printf("mean per frame: keygraph %.2f real (%.2f CPU) ms with %d models",
                kg_total.first / n, kg_total.second / n, data().index.index().model_count());
    if (one_complete)
      std::printf(", %.2f (%.2f) ms with box.png alone", one_total.first / n, one_total.second / n);
    std::printf("\n");
    std::pair<double, double> angled_total{0, 0}, frontal_total{0, 0};
    bool angled_complete = true, frontal_complete = true;
    for (const Frame& f : data().frames) {
      const auto a = reporter.ms("detect_angled/" + f.name);
      angled_complete = angled_complete && a.first > 0;
      angled_total = {angled_total.first + a.first, angled_total.second + a.second};
      const auto b = reporter.ms("detect_frontal/" + f.name);
      frontal_complete = frontal_complete && b.first > 0;
      frontal_total = {frontal_total.first + b.first, frontal_total.second + b.second};
    }
    if (frontal_complete)
      std::printf(
          "frontal configuration (no tilted views, check or completion, 20 leaves): %.2f "
          "(%.2f) ms per frame; the defaults take %.2fx (%.2fx CPU) its time, ORB pipeline "
          "%.2fx (%.2fx CPU) its time\n",
          frontal_total.first / n, frontal_total.second / n, kg_total.first / frontal_total.first,
          kg_total.second / frontal_total.second, orb_total.first / frontal_total.first,
          orb_total.second / frontal_total.second);
    if (angled_complete)
      std::printf(
          "angled opt-in (tilted views to 60 degrees in 2 levels, triangle check, circuit "
          "completion, 10 leaves): %.2f "
          "(%.2f) ms per frame, %.2fx (%.2fx CPU) the defaults', ORB pipeline %.2fx (%.2fx CPU) "
          "slower\n",
          angled_total.first / n, angled_total.second / n, angled_total.first / kg_total.first,
          angled_total.second / kg_total.second, orb_total.first / angled_total.first,
          orb_total.second / angled_total.second);
    // Two threads against one, and a tracked frame against its detection,
    // over the frames where both ran.
    std::pair<double, double> one_thread{0, 0}, two_threads{0, 0}, detected{0, 0}, tracked{0, 0};
    int tracked_frames = 0;
    for (const Frame& f : data().frames) {
      const auto d = reporter.ms("detect/" + f.name);
      const auto t2 = reporter.ms("detect_threads2/" + f.name);
      if (t2.first > 0) {
        one_thread = {one_thread.first + d.first, one_thread.second + d.second};
        two_threads = {two_threads.first + t2.first, two_threads.second + t2.second};
      }
      const auto t = reporter.ms("tracked/" + f.name);
      if (t.first > 0) {
        detected = {detected.first + d.first, detected.second + d.second};
        tracked = {tracked.first + t.first, tracked.second + t.second};
        ++tracked_frames;
      }
    }
    if (two_threads.first > 0)
      // Real time only: the CPU column counts the calling thread alone.
      std::printf("2 threads: %.2fx one thread's speed (real time)\n",
                  one_thread.first / two_threads.first);
    if (tracked_frames > 0)
      std::printf(
          "tracked frame: %.2f (%.2f) ms, %.3fx a detection's time, over the %d frames "
          "with an object to follow\n",
          tracked.first / tracked_frames, tracked.second / tracked_frames,
          tracked.first / detected.first, tracked_frames);
  } else {
    std::printf(
        "(the ratio needs detect/ and orb_pipeline/ of every frame: run without a filter)\n");
  }
}

void register_benchmarks() {
  using Fn = void (*)(benchmark::State&, const Frame*);
  const std::pair<const char*, Fn> kinds[] = {{"detect/", detect_frame},
                                              {"detect_box_only/", detect_box_only},
                                              {"detect_no_appearance/", detect_no_appearance},
                                              {"detect_upsampled/", detect_upsampled},
                                              {"detect_frontal/", detect_frontal},
                                              {"detect_angled/", detect_angled},
                                              {"detect_threads2/", detect_threads2},
                                              {"tracked/", tracked_frame},
                                              {"orb_pipeline/", orb_pipeline},
                                              {"hessian/", hessian_stage},
                                              {"blur/", blur_stage},
                                              {"sampling/", sampling_stage},
                                              {"delaunay/", delaunay_stage},
                                              {"keygraphs/", keygraph_stage},
                                              {"arc_descriptors/", arc_descriptor_stage},
                                              {"arc_search/", arc_search_stage},
                                              {"selection/", selection_stage}};
  for (const auto& [prefix, fn] : kinds) {
    for (const Frame& f : data().frames) {
      benchmark::RegisterBenchmark((prefix + f.name).c_str(), fn, &f)
          ->Unit(benchmark::kMillisecond);
    }
  }
}

}  // namespace
}  // namespace kg

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  cv::setNumThreads(1);  // every pipeline on one thread
  kg::Data& d = kg::data();
  if (kg::Status s = kg::load_models(d); !s) {
    std::fprintf(stderr, "bench_frame: %s\n", s.message().c_str());
    return 1;
  }
  d.frames.resize(std::size(kg::kFrames));
  for (std::size_t i = 0; i < d.frames.size(); ++i) {
    if (kg::Status s = kg::prepare_frame(d, kg::kFrames[i], d.frames[i]); !s) {
      std::fprintf(stderr, "bench_frame: %s\n", s.message().c_str());
      return 1;
    }
  }
  kg::register_benchmarks();
  kg::SummaryReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  kg::print_summary(reporter);
  benchmark::Shutdown();
  return 0;
}
