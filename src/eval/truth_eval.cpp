#include "eval/truth_eval.h"

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <new>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "builder/desktop_detect.h"
#include "builder/image_io.h"
#include "builder/in_memory_index.h"
#include "builder/keypoints.h"
#include "builder/model_set.h"
#include "core/image/upsample.h"
#include "core/index/index_format.h"
#include "core/keygraphs/keygraph.h"
#include "core/pose/point_grid.h"
#include "core/pose/pose.h"
#include "eval/baselines.h"
#include "eval/quad_geometry.h"
#include "keygraph/model_index.h"
#include "platform/files/regular_file.h"

namespace kg {

namespace {

void model_outline(const TruthModel& m, Point2f (&out)[4]) {
  const auto w = static_cast<float>(m.width - 1), h = static_cast<float>(m.height - 1);
  out[0] = {0.f, 0.f};
  out[1] = {w, 0.f};
  out[2] = {w, h};
  out[3] = {0.f, h};
}

double median_of(std::vector<double>& v) {
  if (v.empty()) return -1;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// Median distance, over a 20 x 20 grid of model points whose true image
// lies inside the scene, between where the truth and the detection put them.
double grid_error(const Homography& truth, const Homography& found, const TruthModel& m,
                  int scene_width, int scene_height) {
  constexpr int kSteps = 20;
  std::vector<double> errors;
  for (int j = 0; j < kSteps; ++j) {
    for (int i = 0; i < kSteps; ++i) {
      const Point2f p{static_cast<float>((m.width - 1) * (i + 0.5) / kSteps),
                      static_cast<float>((m.height - 1) * (j + 0.5) / kSteps)};
      const Point2f t = kg::apply(truth, p);
      if (!(t.x >= 0 && t.y >= 0 && t.x <= static_cast<double>(scene_width) - 1 &&
            t.y <= static_cast<double>(scene_height) - 1))
        continue;
      const Point2f f = kg::apply(found, p);
      const double e = std::hypot(double{t.x} - f.x, double{t.y} - f.y);
      errors.push_back(std::isfinite(e) ? e : 1e9);
    }
  }
  return median_of(errors);
}

// Runs an OpenCV call, its exception (out of memory, above all) as a status.
template <typename Call>
Status opencv_call(Call call) {
  try {
    call();
  } catch (const cv::Exception& e) {
    return {StatusCode::kResourceExhausted, "OpenCV: " + e.err};
  } catch (const std::bad_alloc&) {
    return {StatusCode::kResourceExhausted, "out of memory"};
  }
  return Status::ok();
}

bool accepts(const TruthQuad& q, int model) {
  return std::find(q.models.begin(), q.models.end(), model) != q.models.end();
}

// The detectors of one method for one set of searched models.
struct MethodDetectors {
  std::vector<int> models;  // evaluation model index of each detector model id
  std::unique_ptr<InMemoryIndex> index;
  std::unique_ptr<DesktopDetector> keygraph;
  std::unique_ptr<BaselineDetector> baseline;
};

struct Method {
  std::string name;
  bool keygraph = false;
  BaselineOptions baseline;
  Params params;                  // keygraph methods: how the models were built
  std::vector<BuiltModel> built;  // keygraph methods from model images
  // The detectors of the searched model sets met most recently, the
  // latest last: at most kCachedSearches (each holds an index and a
  // workspace, so a manifest of many distinct "search" sets would
  // otherwise grow without bound); an evicted set is built again if it
  // comes back, with the same results.
  std::vector<std::pair<std::string, std::unique_ptr<MethodDetectors>>> by_search;
};

constexpr std::size_t kCachedSearches = 8;

// The detectors for `key`, found or made (empty: to be filled), now the
// most recent.
MethodDetectors& detectors_for(Method& m, const std::string& key) {
  auto it = std::find_if(m.by_search.begin(), m.by_search.end(),
                         [&](const auto& entry) { return entry.first == key; });
  std::pair<std::string, std::unique_ptr<MethodDetectors>> entry;
  if (it != m.by_search.end()) {
    entry = std::move(*it);
    m.by_search.erase(it);
  } else {
    entry = {key, std::make_unique<MethodDetectors>()};
    if (m.by_search.size() >= kCachedSearches) m.by_search.erase(m.by_search.begin());
  }
  m.by_search.push_back(std::move(entry));
  return *m.by_search.back().second;
}

std::string search_key(const std::vector<int>& models) {
  std::string key;
  for (const int m : models) key += std::to_string(m) + ",";
  return key;
}

// The support of each truth instance's pose (TruthCase::truth_*) among
// the frame's keypoints, for a keygraph detector whose model ids are
// `detector_model` of the evaluation's (-1: not in its index).
// `detector` has just searched `gray`: its correspondences are counted too.
void measure_truth_support(const Detector& detector, const std::vector<int>& detector_model,
                           const std::vector<TruthModel>& models, const cv::Mat& gray,
                           const std::vector<TruthQuad>& truth, KeypointExtractor& extractor,
                           std::vector<TruthCase>& cases) {
  const ModelIndex& index = detector.index();
  const Params& params = index.params();
  const int vertices = vertex_count(params.graph.structure);
  const ConstSpan<KeygraphMatch> matches = detector.last_matches();
  const ConstSpan<Keypoint> sampled = detector.last_keypoints();
  // With the whole frame upsampled (scene_upsample 2, or 3's second pass,
  // which last_matches() describes) the detector's keypoints are those of
  // the upsampled frame: the support is measured there, under the true
  // pose scaled to it. With 4 only a window is upsampled: not measured.
  const int upsample = params.keypoints.scene_upsample;
  if ((upsample != 1 && upsample != 2 && upsample != 3) || truth.empty()) return;
  const bool upsampled = upsample != 1;
  cv::Mat work = gray;
  if (upsampled) {
    Plane<std::uint8_t> plane;
    upsample2x(ImageView(gray.data, gray.cols, gray.rows, static_cast<int>(gray.step)), plane);
    work = cv::Mat(plane.height(), plane.width(), CV_8UC1, plane.row(0)).clone();
  }
  std::vector<Keypoint> keypoints;
  extractor.extract(work, params.keypoints, Limits{}.max_keypoints, keypoints);
  PointGrid grid;
  grid.reserve(static_cast<int>(keypoints.size()), work.cols, work.rows,
               std::max(4.f, static_cast<float>(params.ransac.inlier_threshold)));
  grid.build(keypoints.data(), static_cast<int>(keypoints.size()), work.cols, work.rows,
             std::max(4.f, static_cast<float>(params.ransac.inlier_threshold)));
  FrameKeypoints frame;
  frame.keypoints = keypoints.data();
  frame.count = static_cast<int>(keypoints.size());
  frame.grid = &grid;
  frame.width = work.cols;
  frame.height = work.rows;
  const RansacParams& rp = params.ransac;
  // The small-instance rule (ransac.small_*) accepts fewer re-found
  // keypoints for an outline at most small_max_size frame pixels long
  // (with the appearance, not checked here, as for confirmed_*).
  const bool small_rule = rp.small_max_size > 0.f && rp.small_min_inliers > 0 &&
                          index.model_count() > 0 && !index.appearance(0).empty();
  for (std::size_t i = 0; i < truth.size() && i < cases.size(); ++i) {
    const TruthQuad& t = truth[i];
    TruthCase& c = cases[i];
    float truth_long = 0.f;  // the outline's longest side under the pose kept
    for (const int m : t.models) {
      const int id = detector_model[static_cast<std::size_t>(m)];
      if (id < 0) continue;
      Point2f outline[4];
      model_outline(models[static_cast<std::size_t>(m)], outline);
      std::vector<Homography> poses;
      if (t.has_homography) {
        poses.push_back(t.homography);
      } else {
        // The corners' order is unknown: every cyclic shift, both ways.
        std::vector<cv::Point2f> from(4), to(4);
        for (int corner = 0; corner < 4; ++corner)
          from[corner] = {outline[corner].x, outline[corner].y};
        for (int start = 0; start < 4; ++start) {
          for (const int step : {1, 3}) {
            for (int corner = 0; corner < 4; ++corner) {
              const Point2f& q = t.corners[(start + step * corner) % 4];
              to[corner] = {q.x, q.y};
            }
            const cv::Mat h = cv::getPerspectiveTransform(from, to);
            if (h.empty() || !(std::abs(h.at<double>(2, 2)) > 1e-12)) continue;
            Homography pose{};
            for (int e = 0; e < 9; ++e) pose[e] = h.at<double>(e / 3, e % 3) / h.at<double>(2, 2);
            poses.push_back(pose);
          }
        }
      }
      for (const Homography& pose : poses) {
        const PoseSupport s = measure_pose_support(
            index, id, frame, upsampled ? homography_to_upsampled(pose) : pose);
        if (s.refound > c.truth_refound || (s.refound == c.truth_refound && s.z > c.truth_z)) {
          c.truth_shown = s.shown;
          c.truth_refound = s.refound;
          c.truth_z = s.z;
          Point2f corners[4];
          for (int q = 0; q < 4; ++q) corners[q] = kg::apply(pose, outline[q]);
          truth_long = static_cast<float>(longest_side(corners));
          // Correspondences of this model that agree with this pose
          // (sampled: mapped back to frame pixels; the tolerance counts
          // upsampled pixels there, as the pose stage's does).
          const auto tolerance = static_cast<float>(rp.inlier_threshold) * (upsampled ? 0.5f : 1.f);
          c.truth_matches = 0;
          for (const KeygraphMatch& match : matches) {
            if (match.model_id != id) continue;
            bool agrees = true;
            for (int v = 0; v < vertices && agrees; ++v) {
              const auto scene = static_cast<std::size_t>(match.scene_vertices[v]);
              if (scene >= sampled.size()) {
                agrees = false;
                break;
              }
              const Point2f want = kg::apply(pose, index.keypoints()[match.model_vertices[v]]);
              agrees =
                  std::hypot(want.x - sampled[scene].x, want.y - sampled[scene].y) <= tolerance;
            }
            c.truth_matches += agrees ? 1 : 0;
          }
        }
      }
    }
    if (c.truth_refound >= 0) {
      c.truth_enough_matches = c.truth_matches >= rp.min_inlier_keygraphs;
      c.truth_verifiable =
          (c.truth_refound >= rp.min_inliers && c.truth_z >= rp.min_verification_z) ||
          (rp.confirmed_min_inliers > 0 && c.truth_refound >= rp.confirmed_min_inliers &&
           c.truth_z >= rp.confirmed_min_verification_z) ||
          (small_rule && c.truth_refound >= rp.small_min_inliers &&
           c.truth_z >= rp.min_verification_z && truth_long <= rp.small_max_size);
    }
  }
}

}  // namespace

cv::Mat draw_truth_scene(const cv::Mat& gray, const std::vector<TruthQuad>& truth,
                         const std::vector<FoundQuad>& found,
                         const std::vector<DetectionKind>& kinds,
                         const std::vector<TruthModel>& models) {
  cv::Mat canvas;
  cv::cvtColor(gray, canvas, cv::COLOR_GRAY2BGR);
  const int thickness = std::max(1, std::max(gray.cols, gray.rows) / 400);
  auto quad = [&](const Point2f(&c)[4], const cv::Scalar& colour, const std::string& label) {
    std::vector<cv::Point> pts;
    for (const Point2f& p : c) {
      pts.emplace_back(cvRound(std::clamp(p.x, -1e5f, 1e5f)),
                       cvRound(std::clamp(p.y, -1e5f, 1e5f)));
    }
    cv::polylines(canvas, pts, true, colour, thickness, cv::LINE_AA);
    cv::putText(canvas, label, pts[0] + cv::Point(3, -3), cv::FONT_HERSHEY_SIMPLEX, 0.4 * thickness,
                colour, thickness, cv::LINE_AA);
  };
  for (const TruthQuad& t : truth) quad(t.corners, {0, 200, 0}, "truth");  // green
  for (std::size_t i = 0; i < found.size(); ++i) {
    const cv::Scalar colour =
        kinds[i] == DetectionKind::kTrue ? cv::Scalar(255, 120, 0) : cv::Scalar(0, 0, 255);
    quad(found[i].corners, colour,
         models[static_cast<std::size_t>(found[i].model)].name + " (" +
             detection_kind_name(kinds[i]) + ")");
  }
  return canvas;
}

std::vector<TruthQuad> truth_quads(const TruthResults& results, int scene) {
  auto model_id = [&](const std::string& name) {
    for (std::size_t i = 0; i < results.models.size(); ++i) {
      if (results.models[i].name == name) return static_cast<int>(i);
    }
    return -1;
  };
  std::vector<TruthQuad> truth;
  for (const TruthInstance& instance :
       results.manifest.scenes[static_cast<std::size_t>(scene)].instances) {
    TruthQuad q;
    for (const std::string& n : instance.models) q.models.push_back(model_id(n));
    q.has_homography = instance.has_homography;
    q.homography = instance.homography;
    if (instance.has_homography) {
      Point2f outline[4];
      model_outline(results.models[static_cast<std::size_t>(q.models.front())], outline);
      for (int c = 0; c < 4; ++c) q.corners[c] = kg::apply(instance.homography, outline[c]);
    } else {
      std::copy(instance.corners, instance.corners + 4, q.corners);
    }
    truth.push_back(q);
  }
  return truth;
}

const char* detection_kind_name(DetectionKind kind) {
  switch (kind) {
    case DetectionKind::kTrue:
      return "true";
    case DetectionKind::kWrongIdentity:
      return "wrong-identity";
    case DetectionKind::kFalse:
      break;
  }
  return "false";
}

void score_truth_scene(const std::vector<FoundQuad>& found, const std::vector<TruthQuad>& truth,
                       const std::vector<TruthModel>& models, int scene_width, int scene_height,
                       double tolerance, double min_iou, std::vector<TruthCase>& cases,
                       std::vector<DetectionKind>& kinds, std::vector<int>& instance_of) {
  cases.assign(std::max<std::size_t>(truth.size(), 1), TruthCase{});
  kinds.assign(found.size(), DetectionKind::kFalse);
  instance_of.assign(found.size(), -1);
  std::vector<bool> claimed(truth.size(), false);
  for (std::size_t i = 0; i < truth.size(); ++i) {
    TruthCase& c = cases[i];
    const TruthQuad& t = truth[i];
    c.instance = static_cast<int>(i);
    c.long_edge = longest_side(t.corners);
    const TruthModel& first = models[static_cast<std::size_t>(t.models.front())];
    c.scale = std::sqrt(std::abs(signed_area(t.corners)) /
                        (static_cast<double>(first.width) * first.height));
    for (const FoundQuad& f : found) {
      if (!accepts(t, f.model)) continue;
      const double e = order_free_corner_error(t.corners, f.corners);
      if (c.corner_error < 0 || e < c.corner_error) {
        c.corner_error = e;
        if (t.has_homography) {
          c.homography_error =
              grid_error(t.homography, f.homography, models[static_cast<std::size_t>(f.model)],
                         scene_width, scene_height);
        }
      }
      c.iou = std::max(c.iou, quad_iou(t.corners, f.corners));
    }
    c.found = c.corner_error >= 0 && c.corner_error <= tolerance;
    c.found_iou = c.iou >= min_iou;
  }
  for (std::size_t d = 0; d < found.size(); ++d) {
    const FoundQuad& f = found[d];
    for (std::size_t i = 0; i < truth.size(); ++i) {
      const bool on = order_free_corner_error(truth[i].corners, f.corners) <= tolerance ||
                      quad_iou(truth[i].corners, f.corners) >= min_iou;
      if (!on) continue;
      if (accepts(truth[i], f.model)) {
        if (claimed[i]) continue;  // a second detection of the instance is a false one
        claimed[i] = true;
        kinds[d] = DetectionKind::kTrue;
        instance_of[d] = static_cast<int>(i);
        break;
      }
      if (kinds[d] == DetectionKind::kFalse) {
        kinds[d] = DetectionKind::kWrongIdentity;
        instance_of[d] = static_cast<int>(i);
      }
    }
  }
  int wrong = 0, other = 0;
  for (const DetectionKind k : kinds) {
    wrong += k == DetectionKind::kWrongIdentity;
    other += k == DetectionKind::kFalse;
  }
  for (TruthCase& c : cases) {
    c.detections = static_cast<int>(found.size());
    c.wrong_identity = wrong;
    c.false_detections = other;
  }
}

Status evaluate_truth(const TruthEvalOptions& options, TruthResults& results,
                      const ProgressFn& progress,
                      const std::function<Status(const TruthResults&)>& before_work) {
  results = TruthResults{};
  Status s = read_truth_manifest(options.manifest, results.manifest);
  if (!s) return s;
  const TruthManifest& manifest = results.manifest;
  auto at_line = [&](const TruthScene& scene, const std::string& what) {
    return Status{StatusCode::kInvalidArgument,
                  manifest.path + ":" + std::to_string(scene.line) + ": " + what};
  };
  results.inputs.push_back(options.manifest);

  // The models: images, or an index.
  if (options.models.empty() == options.index.empty())
    return {StatusCode::kInvalidArgument, "give one of --models DIR and --index I.kgi"};
  std::vector<ModelSource> sources;
  ModelIndex file_index;
  if (!options.models.empty()) {
    if (s = read_model_sources(options.models, sources); !s) return s;
    results.inputs.push_back(options.models);  // a models.json (a directory is no output)
    for (const ModelSource& m : sources) results.inputs.push_back(m.path);
  } else {
    if (options.params_set)
      return {StatusCode::kInvalidArgument,
              "--set changes how models are built; an --index keeps its own parameters"};
    if (s = ModelIndex::open(options.index, file_index); !s) return s;
    results.inputs.push_back(options.index);
    for (int i = 0; i < file_index.model_count(); ++i) {
      const ModelInfo info = file_index.model(i);
      results.models.push_back(
          {std::string(info.name), static_cast<int>(info.width), static_cast<int>(info.height)});
    }
  }
  std::vector<std::string> names;
  for (const ModelSource& m : sources) names.push_back(m.name);
  for (const TruthModel& m : results.models) names.push_back(m.name);

  // Every line's models and scene file, before any work.
  for (const TruthScene& scene : manifest.scenes) {
    std::string error;
    if (!check_truth_models(scene, names, error)) return at_line(scene, error);
    struct stat info {};
    if (::stat(scene.path.c_str(), &info) != 0)
      return at_line(scene, "scene " + scene.path + ": no such file");
    if (!S_ISREG(info.st_mode))
      return at_line(scene,
                     "scene " + scene.path + ": is " + platform::file_type_name(info.st_mode));
    results.inputs.push_back(scene.path);
  }

  // With an index the baselines have no images: keygraph alone by default.
  const std::vector<std::string> method_names = !options.methods_set && !options.index.empty()
                                                    ? std::vector<std::string>{"keygraph"}
                                                    : options.methods;
  std::vector<Method> methods;
  bool any_baseline = false;
  for (const std::string& name : method_names) {
    Method m;
    m.name = name;
    if (name == "keygraph" || name == "keygraph-mser") {
      m.keygraph = true;
      if (name == "keygraph-mser" && !options.index.empty())
        return {StatusCode::kInvalidArgument,
                "keygraph-mser builds its own models: use --models, not --index"};
    } else if (!parse_baseline(name, m.baseline)) {
      return {StatusCode::kInvalidArgument, "unknown method '" + name + "'"};
    } else if (!options.index.empty()) {
      return {StatusCode::kInvalidArgument,
              name + " needs the model images: use --models, not --index"};
    } else {
      any_baseline = true;
    }
    if (std::find(results.methods.begin(), results.methods.end(), name) != results.methods.end())
      continue;  // named twice: once is enough
    results.methods.push_back(name);
    methods.push_back(std::move(m));
  }
  if (methods.empty()) return {StatusCode::kInvalidArgument, "no methods"};
  if (before_work) {
    if (s = before_work(results); !s) return s;
  }

  // Build the models (after every check: building is the slow part).
  std::vector<cv::Mat> grays;
  cv::setNumThreads(1);  // every method on one thread
  for (Method& m : methods) {
    if (!m.keygraph || !options.index.empty()) continue;
    ModelBuildOptions build;
    build.params = options.params;
    if (m.name == "keygraph-mser") build.params.keypoints.detector = KeypointDetector::kMser;
    if (s = build_model_set(sources, build, load_gray, grays, m.built); !s) return s;
    m.params = build.params;
  }
  if (!sources.empty() && grays.empty()) {
    if (s = load_model_images(sources, nullptr, load_gray, grays); !s) return s;
  }
  for (std::size_t i = 0; i < sources.size(); ++i) {
    if (any_baseline && static_cast<long long>(grays[i].cols) * grays[i].rows > kMaxBaselinePixels)
      return {StatusCode::kResourceExhausted,
              sources[i].path + ": " + over_baseline_limit(grays[i].cols, grays[i].rows)};
    results.models.push_back({sources[i].name, grays[i].cols, grays[i].rows});
  }
  auto model_id = [&](const std::string& name) {
    for (std::size_t i = 0; i < results.models.size(); ++i) {
      if (results.models[i].name == name) return static_cast<int>(i);
    }
    return -1;
  };
  // Homography truth through the models' outlines: a pose that maps the
  // outline through infinity has no size or scale to score by.
  for (std::size_t si = 0; si < manifest.scenes.size(); ++si) {
    for (const TruthQuad& q : truth_quads(results, static_cast<int>(si))) {
      if (q.has_homography && !is_simple_quad(q.corners))
        return at_line(manifest.scenes[si],
                       "\"homography\" does not map the model's outline to a quadrilateral in "
                       "the scene");
    }
  }

  using Clock = std::chrono::steady_clock;
  KeypointExtractor extractor;  // the frame's keypoints for measure_truth_support()
  const int scene_count = static_cast<int>(manifest.scenes.size());
  for (int si = 0; si < scene_count; ++si) {
    const TruthScene& scene = manifest.scenes[static_cast<std::size_t>(si)];
    cv::Mat gray;
    if (s = load_gray(scene.path, gray); !s) return at_line(scene, s.message());
    if (any_baseline && static_cast<long long>(gray.cols) * gray.rows > kMaxBaselinePixels)
      return at_line(scene,
                     "scene " + scene.path + ": " + over_baseline_limit(gray.cols, gray.rows));
    const std::vector<TruthQuad> truth = truth_quads(results, si);
    std::vector<int> searched;
    for (const std::string& n : scene.search) searched.push_back(model_id(n));
    if (searched.empty()) {
      for (std::size_t i = 0; i < results.models.size(); ++i)
        searched.push_back(static_cast<int>(i));
    }
    std::sort(searched.begin(), searched.end());
    searched.erase(std::unique(searched.begin(), searched.end()), searched.end());

    for (Method& m : methods) {
      MethodDetectors& d = detectors_for(m, search_key(searched));
      if (d.models.empty()) {
        d.models = searched;
        // The workspace for this scene's size now, not inside the timed detect().
        const Limits limits = Limits{}.for_frame(std::max(gray.cols, Limits{}.max_width),
                                                 std::max(gray.rows, Limits{}.max_height));
        if (m.keygraph && !options.index.empty()) {
          // The file's index as it is: other models' detections are dropped below.
          d.keygraph = std::make_unique<DesktopDetector>(file_index, limits, options.detector);
        } else if (m.keygraph) {
          std::vector<BuiltModel> subset;
          for (const int id : searched) subset.push_back(m.built[static_cast<std::size_t>(id)]);
          d.index = std::make_unique<InMemoryIndex>();
          if (s = d.index->build(subset, m.params); !s) return s;
          d.keygraph =
              std::make_unique<DesktopDetector>(d.index->index(), limits, options.detector);
        } else {
          std::vector<cv::Mat> subset;
          for (const int id : searched) subset.push_back(grays[static_cast<std::size_t>(id)]);
          d.baseline = std::make_unique<BaselineDetector>(m.baseline);
          if (s = opencv_call([&] { d.baseline->set_models(subset); }); !s)
            return at_line(scene, m.name + ": " + s.message());
        }
      }
      std::vector<FoundQuad> found;
      const auto start = Clock::now();
      if (d.keygraph) {
        DetectionList list;
        s = d.keygraph->detect(gray, list);
        if (!s) return at_line(scene, m.name + ": " + s.message());
        for (const Detection& det : list) {
          FoundQuad f;
          f.model = options.index.empty() ? d.models[static_cast<std::size_t>(det.model_id)]
                                          : det.model_id;
          f.homography = det.homography;
          std::copy(det.corners, det.corners + 4, f.corners);
          found.push_back(f);
        }
      } else {
        std::vector<BaselineDetection> list;
        if (s = opencv_call([&] { d.baseline->detect(gray, list); }); !s)
          return at_line(scene, m.name + ": " + s.message());
        for (const BaselineDetection& det : list) {
          FoundQuad f;
          f.model = d.models[static_cast<std::size_t>(det.model_id)];
          f.homography = det.homography;
          std::copy(det.corners, det.corners + 4, f.corners);
          found.push_back(f);
        }
      }
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
      if (progress) {
        const int method_count = static_cast<int>(methods.size());
        progress(si * method_count + static_cast<int>(&m - methods.data()) + 1,
                 scene_count * method_count, m.name + ", scene " + std::to_string(si + 1));
      }
      // A file index searches all its models: keep the scene's own.
      found.erase(std::remove_if(found.begin(), found.end(),
                                 [&](const FoundQuad& f) {
                                   return !std::binary_search(searched.begin(), searched.end(),
                                                              f.model);
                                 }),
                  found.end());

      std::vector<TruthCase> cases;
      std::vector<DetectionKind> kinds;
      std::vector<int> instance_of;
      score_truth_scene(found, truth, results.models, gray.cols, gray.rows, options.tolerance,
                        options.min_iou, cases, kinds, instance_of);
      if (d.keygraph) {
        std::vector<int> detector_model(results.models.size(), -1);
        for (std::size_t i = 0; i < results.models.size(); ++i) {
          if (!options.index.empty()) {
            detector_model[i] = static_cast<int>(i);
          } else {
            const auto at = std::lower_bound(d.models.begin(), d.models.end(), static_cast<int>(i));
            if (at != d.models.end() && *at == static_cast<int>(i))
              detector_model[i] = static_cast<int>(at - d.models.begin());
          }
        }
        measure_truth_support(d.keygraph->core(), detector_model, results.models, gray, truth,
                              extractor, cases);
      }
      bool interesting = false;
      for (TruthCase& c : cases) {
        c.method = m.name;
        c.scene = si;
        c.time_ms = ms;
        if (truth.empty()) c.instance = -1;
        interesting = interesting || (!truth.empty() && !c.found);
        results.cases.push_back(c);
      }
      for (std::size_t i = 0; i < found.size(); ++i) {
        TruthDetection t;
        t.method = m.name;
        t.scene = si;
        t.model = found[i].model;
        std::copy(found[i].corners, found[i].corners + 4, t.corners);
        t.kind = kinds[i];
        t.instance = instance_of[i];
        interesting = interesting || kinds[i] != DetectionKind::kTrue;
        results.detections.push_back(t);
      }
      if (options.gallery && interesting) results.gallery.push_back({m.name, si});
    }
  }
  return Status::ok();
}

}  // namespace kg
