#include "eval/oxford.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>

#include <opencv2/imgproc.hpp>

#include "builder/desktop_detect.h"
#include "builder/image_io.h"
#include "builder/in_memory_index.h"
#include "builder/model_builder.h"
#include "core/pose/appearance_align.h"
#include "core/support/rng.h"
#include "eval/baselines.h"
#include "eval/correspondence_pr.h"
#include "eval/set_files.h"

namespace kg {

Status read_homography(const std::string& path, Homography& h) {
  return read_homography_file(path, h);
}

namespace {

// The appearance's long edge for the correlations: the index's default,
// whatever --set views.appearance_size says (the measurement is the same
// for every configuration and method).
constexpr int kCorrelationAppearanceSize = ViewParams{}.appearance_size;

// OxfordCase::truth_correlation and found_correlation: the correlation
// the appearance aligner measures at the pose it is given (its
// refinement, which follows, is left unused).
double pose_correlation(AppearanceAligner& aligner, const cv::Mat& appearance, float scale,
                        const cv::Mat& blurred_scene, const Homography& pose) {
  Homography h = pose;
  const AppearanceFit fit =
      aligner.align({appearance.data, appearance.cols, appearance.rows, scale, scale},
                    ImageView(blurred_scene.data, blurred_scene.cols, blurred_scene.rows,
                              static_cast<std::ptrdiff_t>(blurred_scene.step)),
                    h);
  return fit.measured ? fit.ncc_before : -1.0;
}

Homography compose_with_offset(const Homography& h, double dx, double dy) {
  // H * [1 0 dx; 0 1 dy; 0 0 1]
  Homography g = h;
  for (int r = 0; r < 3; ++r) g[r * 3 + 2] = h[r * 3 + 0] * dx + h[r * 3 + 1] * dy + h[r * 3 + 2];
  return g;
}

// A keygraph method for one crop: the timed detector and, for curves, the
// selection at the grid's largest threshold.
struct KeygraphRun {
  std::string name;
  Params params;
  BuiltModel model;
  InMemoryIndex index, curve_index;
  std::unique_ptr<DesktopDetector> detector, curve_detector;
  cv::Mat model_sift;
};

constexpr Limits curve_limits() {
  Limits l;
  l.max_arc_matches = 1 << 16;
  l.max_arc_pool = 1 << 25;
  l.max_correspondences = 1 << 21;
  return l;
}

// Selection only (one RANSAC iteration, one attempt), float32 descriptors,
// every correspondence up to the largest arc threshold.
Params curve_params(Params p, double max_threshold) {
  p.descriptor.similarity_threshold = static_cast<float>(max_threshold);
  p.descriptor.encoding = DescriptorEncoding::kFloat32;
  p.ransac.max_iterations = 1;
  p.ransac.max_instances = 1;
  return p;
}

// The curves of one positive case (see OxfordEvalOptions::curves).
Status measure_curves(KeygraphRun& run, const cv::Mat& scene, const Homography& truth,
                      double tolerance, const OxfordCurveGrids& grids, OxfordCase& r) {
  DetectionList ignored;
  Status s = run.curve_detector->detect(scene, ignored);
  if (!s) return s;
  const Detector& core = run.curve_detector->core();
  const DetectStats& stats = core.stats();
  r.curve_truncated = stats.truncated_arc_matches || stats.truncated_correspondences;
  const std::vector<Keypoint> keypoints(core.last_keypoints().begin(), core.last_keypoints().end());
  const std::vector<KeygraphMatch> matches(core.last_matches().begin(), core.last_matches().end());
  const int count = static_cast<int>(keypoints.size());
  CorrespondenceTruth truths;
  truths.build(run.model.keypoints, keypoints.data(), count, truth, tolerance);
  const cv::Mat blurred = blur_for_descriptors(scene, run.params.descriptor.blur_sigma);
  r.keygraph_curve =
      keygraph_curve(run.model, core.index().model(0).keypoint_begin, blurred, keypoints.data(),
                     count, matches, 0, run.curve_index.index().params(), truths, grids.arc);
  keypoint_curves(run.model_sift, unit_sift(scene, keypoints), truths, grids.sift_distance,
                  grids.sift_ratio, r.sift_distance_curve, r.sift_ratio_curve);
  r.has_curves = true;
  r.model_keypoints = static_cast<int>(run.model.keypoints.size());
  r.scene_keypoints = count;
  // Repeatability, both ways, within the part of each image the other shows.
  for (std::size_t m = 0; m < run.model.keypoints.size(); ++m) {
    const Point2f p = kg::apply(truth, run.model.keypoints[m]);
    if (!(p.x >= 0 && p.y >= 0 && double{p.x} <= scene.cols - 1 && double{p.y} <= scene.rows - 1))
      continue;
    ++r.model_inside;
    r.model_repeated += !truths.of(static_cast<std::uint32_t>(m)).empty();
  }
  const float w = static_cast<float>(run.model.width - 1),
              h = static_cast<float>(run.model.height - 1);
  std::vector<cv::Point2f> outline;
  for (const Point2f& c : {Point2f{0, 0}, Point2f{w, 0}, Point2f{w, h}, Point2f{0, h}}) {
    const Point2f p = kg::apply(truth, c);
    outline.emplace_back(p.x, p.y);
  }
  for (int i = 0; i < count; ++i) {
    if (cv::pointPolygonTest(outline,
                             cv::Point2f(keypoints[static_cast<std::size_t>(i)].x,
                                         keypoints[static_cast<std::size_t>(i)].y),
                             false) < 0)
      continue;
    ++r.scene_inside;
    r.scene_repeated += truths.scene_repeated(i);
  }
  return Status::ok();
}

}  // namespace

OxfordCurveGrids oxford_curve_grids() {
  OxfordCurveGrids g;
  g.arc = threshold_grid(0.0, 0.5, 0.01);
  g.sift_distance = threshold_grid(0.0, 1.42, 0.02);
  g.sift_ratio = threshold_grid(0.0, 1.0, 0.02);
  return g;
}

Status evaluate_oxford(const OxfordEvalOptions& options, std::vector<OxfordCase>& cases,
                       const ProgressFn& progress) {
  namespace fs = std::filesystem;
  cases.clear();
  std::vector<std::string> subsets = options.subsets;
  std::error_code ec;
  if (!fs::is_directory(options.dataset, ec))
    return {StatusCode::kNotFound, options.dataset + ": no such directory"};
  if (subsets.empty()) {
    for (const auto& entry : fs::directory_iterator(options.dataset, ec)) {
      if (fs::exists(entry.path() / "img1.png"))
        subsets.push_back(entry.path().filename().string());
    }
    std::sort(subsets.begin(), subsets.end());
  }
  if (subsets.empty()) return {StatusCode::kNotFound, options.dataset + ": no <subset>/img1.png"};
  cv::setNumThreads(1);  // every method on one thread
  std::vector<BaselineDetector> baselines;
  std::vector<std::string> baseline_methods;
  std::vector<KeygraphRun> keygraphs;
  for (const std::string& m : options.methods) {
    BaselineOptions b;
    if (m == "keygraph" || m == "keygraph-mser") {
      KeygraphRun run;
      run.name = m;
      run.params = options.params;
      if (m == "keygraph-mser") run.params.keypoints.detector = KeypointDetector::kMser;
      keygraphs.push_back(std::move(run));
    } else if (parse_baseline(m, b)) {
      baselines.emplace_back(b);
      baseline_methods.push_back(m);
    } else {
      return {StatusCode::kInvalidArgument, "unknown method '" + m + "'"};
    }
  }
  const OxfordCurveGrids grids = oxford_curve_grids();
  // Scenes and ground truth of every subset (negatives use the next one's).
  struct Subset {
    cv::Mat img1;
    std::vector<cv::Mat> scenes = std::vector<cv::Mat>(7);
    std::vector<Homography> truths = std::vector<Homography>(7);
  };
  std::vector<Subset> data(subsets.size());
  for (std::size_t i = 0; i < subsets.size(); ++i) {
    const std::string dir = options.dataset + "/" + subsets[i];
    Status s = load_gray(dir + "/img1.png", data[i].img1);
    if (!s) return s;
    for (int n = 2; n <= 6; ++n) {
      s = load_gray(dir + "/img" + std::to_string(n) + ".png", data[i].scenes[n]);
      if (!s) return s;
      s = read_homography(dir + "/H1to" + std::to_string(n) + "p", data[i].truths[n]);
      if (!s) return s;
    }
    if (data[i].img1.cols < options.crop_size || data[i].img1.rows < options.crop_size)
      return {StatusCode::kInvalidArgument, dir + "/img1.png smaller than the crop size"};
  }
  using Clock = std::chrono::steady_clock;
  // Cases: subsets x crops x scene sets x 5 scenes x methods.
  const int total_cases = static_cast<int>(subsets.size()) *
                          (options.centre_crop ? 1 : options.crops_per_subset) *
                          (options.negatives && subsets.size() > 1 ? 2 : 1) * 5 *
                          static_cast<int>(baselines.size() + keygraphs.size());
  Rng rng(options.seed);
  for (std::size_t si = 0; si < subsets.size(); ++si) {
    const cv::Mat& img1 = data[si].img1;
    const int size = options.crop_size;
    const int crops = options.centre_crop ? 1 : options.crops_per_subset;
    for (int c = 0; c < crops; ++c) {
      int x = (img1.cols - size) / 2, y = (img1.rows - size) / 2;
      if (!options.centre_crop) {
        x = static_cast<int>(rng.uniform(static_cast<std::uint32_t>(img1.cols - size + 1)));
        y = static_cast<int>(rng.uniform(static_cast<std::uint32_t>(img1.rows - size + 1)));
      }
      const cv::Mat crop = img1(cv::Rect(x, y, size, size)).clone();
      cv::Mat appearance;
      float appearance_scale = 1.f;
      model_appearance(crop, kCorrelationAppearanceSize, appearance, appearance_scale);
      AppearanceAligner aligner;
      aligner.reserve(appearance.cols * appearance.rows);
      for (KeygraphRun& run : keygraphs) {
        const std::string where = subsets[si] + " crop " + std::to_string(c) + ": ";
        Status s = build_model(crop, "crop", run.params, run.model);
        if (s) s = run.index.build({run.model}, run.params);
        if (!s) return {s.code(), where + s.message()};
        run.detector =
            std::make_unique<DesktopDetector>(run.index.index(), Limits{}, options.detector);
        if (options.curves) {
          s = run.curve_index.build({run.model}, curve_params(run.params, grids.arc.back()));
          if (!s) return {s.code(), where + s.message()};
          run.curve_detector =
              std::make_unique<DesktopDetector>(run.curve_index.index(), curve_limits());
          std::vector<Keypoint> keypoints;
          for (std::size_t k = 0; k < run.model.keypoints.size(); ++k) {
            keypoints.push_back({run.model.keypoints[k].x, run.model.keypoints[k].y,
                                 run.model.keypoint_scales[k], 0.f});
          }
          run.model_sift = unit_sift(crop, keypoints);
        }
      }
      for (BaselineDetector& b : baselines) b.set_model(crop);
      const Point2f outline[4] = {{0.f, 0.f},
                                  {static_cast<float>(size - 1), 0.f},
                                  {static_cast<float>(size - 1), static_cast<float>(size - 1)},
                                  {0.f, static_cast<float>(size - 1)}};
      const int scene_sets = options.negatives && subsets.size() > 1 ? 2 : 1;
      for (int set = 0; set < scene_sets; ++set) {
        const std::size_t ti = set == 0 ? si : (si + 1) % subsets.size();
        for (int n = 2; n <= 6; ++n) {
          const cv::Mat& scene = data[ti].scenes[n];
          const Homography truth = compose_with_offset(data[ti].truths[n], x, y);
          cv::Mat blurred;
          double truth_correlation = -1.0;
          if (set == 0) {
            blurred = blur_for_descriptors(scene, options.params.descriptor.blur_sigma);
            truth_correlation =
                pose_correlation(aligner, appearance, appearance_scale, blurred, truth);
          }
          for (std::size_t m = 0; m < baselines.size() + keygraphs.size(); ++m) {
            OxfordCase r;
            r.subset = subsets[si];
            r.scene_subset = subsets[ti];
            r.negative = set == 1;
            r.crop = c;
            r.crop_x = x;
            r.crop_y = y;
            r.degree = n;
            Homography found_h{};
            const auto start = Clock::now();
            if (m >= baselines.size()) {
              KeygraphRun& run = keygraphs[m - baselines.size()];
              r.method = run.name;
              DetectionList found;
              Status s = run.detector->detect(scene, found);
              r.time_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
              if (!s) return s;
              r.ransac_iterations = run.detector->stats().ransac_iterations;
              r.correspondences = run.detector->stats().correspondences;
              r.detected = !found.empty();
              if (r.detected) {
                r.inliers = found[0].inliers;
                r.first_ransac_iterations = found[0].ransac_iterations;
                found_h = found[0].homography;
              }
              if (options.curves && !r.negative) {
                s = measure_curves(run, scene, truth, options.curve_tolerance, grids, r);
                if (!s) return s;
              }
            } else {
              r.method = baseline_methods[m];
              baselines[m].detect(scene, r.detected, found_h, r.inliers);
              r.time_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
            }
            r.truth_correlation = truth_correlation;
            if (r.detected && !r.negative)
              r.found_correlation =
                  pose_correlation(aligner, appearance, appearance_scale, blurred, found_h);
            if (r.detected) {
              r.corner_error = 0;
              for (const Point2f& corner : outline) {
                const Point2f g = kg::apply(truth, corner);
                const Point2f d = kg::apply(found_h, corner);
                r.corner_error =
                    std::max(r.corner_error, std::hypot(double{g.x} - d.x, double{g.y} - d.y));
              }
            }
            cases.push_back(std::move(r));
            if (progress) {
              const OxfordCase& last = cases.back();
              progress(static_cast<int>(cases.size()), total_cases,
                       last.method + " " + last.subset + " crop " + std::to_string(last.crop) +
                           " img" + std::to_string(last.degree));
            }
          }
        }
      }
    }
  }
  return Status::ok();
}

}  // namespace kg
