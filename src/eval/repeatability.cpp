#include "eval/repeatability.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>

#include <opencv2/features2d.hpp>

#include "builder/image_io.h"
#include "builder/keypoints.h"
#include "core/index/index_format.h"
#include "core/keygraphs/delaunay.h"
#include "core/pose/point_grid.h"
#include "core/sampling/sampling.h"
#include "eval/oxford.h"
#include "keygraph/param_text.h"

namespace kg {

namespace {

bool parse_method(const std::string& name, RepeatabilityMethod& out) {
  static const std::pair<const char*, RepeatabilityMethod> kNames[] = {
      {"hessian", RepeatabilityMethod::kHessian},
      {"mser", RepeatabilityMethod::kMser},
      {"sift", RepeatabilityMethod::kSift},
      {"orb", RepeatabilityMethod::kOrb},
      {"akaze", RepeatabilityMethod::kAkaze}};
  for (const auto& [n, m] : kNames) {
    if (name == n) {
      out = m;
      return true;
    }
  }
  return false;
}

bool inside(Point2f p, cv::Size size) {
  return p.x >= 0.f && p.y >= 0.f && p.x <= static_cast<float>(size.width - 1) &&
         p.y <= static_cast<float>(size.height - 1);
}

Homography inverse(const Homography& h) {
  const cv::Matx33d inv = cv::Matx33d(h.data()).inv();
  Homography out;
  std::copy(inv.val, inv.val + 9, out.begin());
  return out;
}

}  // namespace

Status parse_repeatability_detector(const std::string& text, const Params& base,
                                    RepeatabilityDetector& out) {
  out = RepeatabilityDetector{};
  out.label = text;
  out.params = base;
  std::vector<std::string> parts;
  std::size_t from = 0;
  for (std::size_t colon; (colon = text.find(':', from)) != std::string::npos; from = colon + 1)
    parts.push_back(text.substr(from, colon - from));
  parts.push_back(text.substr(from));
  if (!parse_method(parts[0], out.method))
    return {StatusCode::kInvalidArgument,
            "unknown detector '" + parts[0] + "' (hessian, mser, sift, orb, akaze)"};
  const bool own =
      out.method == RepeatabilityMethod::kHessian || out.method == RepeatabilityMethod::kMser;
  if (parts.size() > 1 && !own)
    return {StatusCode::kInvalidArgument,
            "detector '" + text + "': only hessian and mser take settings"};
  for (std::size_t i = 1; i < parts.size(); ++i) {
    // "threshold=..." is short for "keypoints.hessian_threshold=...".
    const std::string setting = parts[i].find('.') < parts[i].find('=')
                                    ? parts[i]
                                    : "keypoints." + parts[0] + "_" + parts[i];
    if (Status s = set_param(out.params, setting); !s)
      return {s.code(), "detector '" + text + "': " + s.message()};
  }
  out.params.keypoints.detector = out.method == RepeatabilityMethod::kMser
                                      ? KeypointDetector::kMser
                                      : KeypointDetector::kHessian;
  if (Status s = format::validate_params(out.params); !s)
    return {s.code(), "detector '" + text + "': " + s.message()};
  return Status::ok();
}

struct RepeatabilityKeypoints::Impl {
  RepeatabilityDetector detector;
  KeypointExtractor extractor;
  cv::Ptr<cv::Feature2D> features;  // OpenCV's detectors
  std::vector<cv::KeyPoint> found;
};

RepeatabilityKeypoints::RepeatabilityKeypoints(const RepeatabilityDetector& detector)
    : impl_(std::make_unique<Impl>()) {
  impl_->detector = detector;
  switch (detector.method) {
    case RepeatabilityMethod::kSift:
      impl_->features = cv::SIFT::create();
      break;
    case RepeatabilityMethod::kOrb:
      impl_->features = cv::ORB::create(2000);  // as eval/baselines.cpp
      break;
    case RepeatabilityMethod::kAkaze:
      impl_->features = cv::AKAZE::create();
      break;
    case RepeatabilityMethod::kHessian:
    case RepeatabilityMethod::kMser:
      break;
  }
}

RepeatabilityKeypoints::~RepeatabilityKeypoints() = default;

void RepeatabilityKeypoints::detect(const cv::Mat& gray, int max_keypoints,
                                    std::vector<Keypoint>& out) {
  out.clear();
  if (!impl_->features) {
    impl_->extractor.extract(gray, impl_->detector.params.keypoints, max_keypoints, out);
    return;
  }
  impl_->features->detect(gray, impl_->found);
  for (const cv::KeyPoint& k : impl_->found)
    out.push_back({k.pt.x, k.pt.y, k.size / 2, k.response});
  std::stable_sort(out.begin(), out.end(),
                   [](const Keypoint& a, const Keypoint& b) { return a.response > b.response; });
  if (static_cast<int>(out.size()) > max_keypoints)
    out.resize(static_cast<std::size_t>(std::max(0, max_keypoints)));
}

RepeatabilityParams repeatability_params(const Params& params, const Limits& limits,
                                         double tolerance) {
  RepeatabilityParams p;
  p.tolerance = tolerance;
  p.sample_distance = params.graph.scene_sample_distance;
  p.min_arc = params.graph.min_distance;
  p.max_arc = params.graph.max_distance;
  p.max_scene_keypoints = limits.max_scene_keypoints;
  return p;
}

PairRepeatability measure_repeatability(const std::vector<Keypoint>& model, cv::Size model_size,
                                        const std::vector<Keypoint>& scene, cv::Size scene_size,
                                        const Homography& model_to_scene,
                                        const RepeatabilityParams& params) {
  PairRepeatability r;
  r.model_keypoints = static_cast<int>(model.size());
  r.scene_keypoints = static_cast<int>(scene.size());
  const auto tolerance = static_cast<float>(params.tolerance);
  const float cell = std::max(tolerance, 1.f);

  // Model keypoints against every scene keypoint, at the true pose and
  // shifted.
  PointGrid scene_grid;
  scene_grid.build(scene.data(), r.scene_keypoints, scene_size.width, scene_size.height, cell);
  // Projections near the scene (where a scene keypoint, shifted or not,
  // can be within the tolerance), and their model keypoints: the grid
  // takes no far or non-finite positions.
  const float margin = std::abs(params.chance_shift) + tolerance + 1.f;
  std::vector<Keypoint> projected;
  std::vector<int> projected_model;
  for (std::size_t i = 0; i < model.size(); ++i) {
    const Point2f p = apply(model_to_scene, Point2f{model[i].x, model[i].y});
    if (p.x >= -margin && p.y >= -margin &&
        p.x <= static_cast<float>(scene_size.width - 1) + margin &&
        p.y <= static_cast<float>(scene_size.height - 1) + margin) {
      projected.push_back({p.x, p.y, model[i].scale, model[i].response});
      projected_model.push_back(static_cast<int>(i));
    }
    if (inside(p, scene_size)) {
      ++r.model_inside;
      r.model_repeated += scene_grid.nearest(p, tolerance) >= 0;
    }
    const Point2f q{p.x + params.chance_shift, p.y + params.chance_shift};
    if (inside(q, scene_size)) {
      ++r.model_inside_shifted;
      r.model_repeated_shifted += scene_grid.nearest(q, tolerance) >= 0;
    }
  }

  // Sampled scene keypoints against every projected model keypoint.
  std::vector<int> selected;
  SeparatedSampler sampler;
  sampler.sample(scene.data(), r.scene_keypoints, params.sample_distance, nullptr, selected);
  if (static_cast<int>(selected.size()) > params.max_scene_keypoints)
    selected.resize(static_cast<std::size_t>(std::max(0, params.max_scene_keypoints)));
  r.sampled = static_cast<int>(selected.size());
  PointGrid model_grid;
  model_grid.build(projected.data(), static_cast<int>(projected.size()), scene_size.width,
                   scene_size.height, cell);
  const Homography scene_to_model = inverse(model_to_scene);
  std::vector<Point2f> points;
  std::vector<char> in_view;
  // Model keypoint within the tolerance (of the keypoint shifted), or -1.
  std::vector<int> counterpart, shifted;
  for (int i : selected) {
    const Point2f p{scene[static_cast<std::size_t>(i)].x, scene[static_cast<std::size_t>(i)].y};
    const Point2f q{p.x + params.chance_shift, p.y + params.chance_shift};
    points.push_back(p);
    in_view.push_back(inside(apply(scene_to_model, p), model_size));
    const int near = in_view.back() ? model_grid.nearest(p, tolerance) : -1;
    const int near_shifted = in_view.back() ? model_grid.nearest(q, tolerance) : -1;
    counterpart.push_back(near >= 0 ? projected_model[static_cast<std::size_t>(near)] : -1);
    shifted.push_back(near_shifted >= 0 ? projected_model[static_cast<std::size_t>(near_shifted)]
                                        : -1);
    r.sampled_inside += in_view.back();
    r.sampled_repeated += counterpart.back() >= 0;
    r.sampled_repeated_shifted += shifted.back() >= 0;
  }
  Delaunay delaunay;
  delaunay.triangulate(points.data(), static_cast<int>(points.size()));
  const auto is_arc = [&](int a, int b) {
    const float d = chebyshev(
        Point2f{model[static_cast<std::size_t>(a)].x, model[static_cast<std::size_t>(a)].y},
        Point2f{model[static_cast<std::size_t>(b)].x, model[static_cast<std::size_t>(b)].y});
    return a != b && d >= params.min_arc && d <= params.max_arc;
  };
  const auto& tri = delaunay.triangles();
  for (std::size_t t = 0; t + 2 < tri.size(); t += 3) {
    const auto a = static_cast<std::size_t>(tri[t]), b = static_cast<std::size_t>(tri[t + 1]),
               c = static_cast<std::size_t>(tri[t + 2]);
    if (!in_view[a] || !in_view[b] || !in_view[c]) continue;
    ++r.triangles;
    const auto keygraph = [&](int ma, int mb, int mc) {
      return ma >= 0 && mb >= 0 && mc >= 0 && is_arc(ma, mb) && is_arc(mb, mc) && is_arc(mc, ma);
    };
    r.triangles_keygraph_shifted += keygraph(shifted[a], shifted[b], shifted[c]);
    if (counterpart[a] < 0 || counterpart[b] < 0 || counterpart[c] < 0) continue;
    ++r.triangles_repeated;
    r.triangles_keygraph += keygraph(counterpart[a], counterpart[b], counterpart[c]);
  }
  return r;
}

Status evaluate_repeatability(const RepeatabilityOptions& options,
                              std::vector<RepeatabilityCase>& cases,
                              std::vector<DetectionTiming>& timings,
                              void (*progress)(const std::string& detector,
                                               const std::string& subset)) {
  namespace fs = std::filesystem;
  using Clock = std::chrono::steady_clock;
  cases.clear();
  timings.clear();
  std::error_code ec;
  if (!fs::is_directory(options.dataset, ec))
    return {StatusCode::kNotFound, options.dataset + ": no such directory"};
  if (options.detectors.empty()) return {StatusCode::kInvalidArgument, "no detectors given"};
  if (options.limits.max_keypoints < 1 || options.limits.max_scene_keypoints < 1)
    return {StatusCode::kInvalidArgument, "keypoint limits must be at least 1"};
  if (!(options.tolerance > 0))
    return {StatusCode::kInvalidArgument, "the tolerance must be positive"};
  std::vector<std::string> subsets = options.subsets;
  if (subsets.empty()) {
    for (const auto& entry : fs::directory_iterator(options.dataset, ec)) {
      if (entry.is_directory() && fs::exists(entry.path() / "img1.png"))
        subsets.push_back(entry.path().filename().string());
    }
    std::sort(subsets.begin(), subsets.end());
    if (subsets.empty())
      return {StatusCode::kNotFound, options.dataset + ": no subset with img1.png"};
  }

  for (const std::string& subset : subsets) {
    const fs::path dir = fs::path(options.dataset) / subset;
    std::vector<cv::Mat> images(6);
    std::vector<Homography> truths(6);
    for (int n = 1; n <= 6; ++n) {
      const auto i = static_cast<std::size_t>(n - 1);
      if (Status s = load_gray((dir / ("img" + std::to_string(n) + ".png")).string(), images[i]);
          !s)
        return s;
      if (n > 1) {
        if (Status s =
                read_homography((dir / ("H1to" + std::to_string(n) + "p")).string(), truths[i]);
            !s)
          return s;
      }
    }
    for (const RepeatabilityDetector& detector : options.detectors) {
      RepeatabilityKeypoints keypoints(detector);
      std::vector<std::vector<Keypoint>> found(6);
      for (std::size_t i = 0; i < 6; ++i) {
        const auto start = Clock::now();
        keypoints.detect(images[i], options.limits.max_keypoints, found[i]);
        DetectionTiming t;
        t.ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
        t.detector = detector.label;
        t.subset = subset;
        t.image = static_cast<int>(i) + 1;
        t.pixels = images[i].cols * images[i].rows;
        t.keypoints = static_cast<int>(found[i].size());
        timings.push_back(t);
      }
      const RepeatabilityParams params =
          repeatability_params(detector.params, options.limits, options.tolerance);
      for (std::size_t i = 1; i < 6; ++i) {
        RepeatabilityCase c;
        c.detector = detector.label;
        c.subset = subset;
        c.degree = static_cast<int>(i) + 1;
        c.counts = measure_repeatability(found[0], images[0].size(), found[i], images[i].size(),
                                         truths[i], params);
        cases.push_back(c);
      }
      if (progress) progress(detector.label, subset);
    }
  }
  return Status::ok();
}

}  // namespace kg
