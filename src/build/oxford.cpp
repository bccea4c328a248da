#include "build/oxford.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>

#include "build/baselines.h"
#include "build/desktop_detect.h"
#include "build/image_io.h"
#include "build/model_builder.h"
#include "core/rng.h"

namespace kg {

Status read_homography(const std::string& path, Homography& h) {
  std::ifstream in(path);
  if (!in) return {StatusCode::kNotFound, path + ": no such file"};
  for (double& v : h) {
    if (!(in >> v) || !std::isfinite(v))
      return {StatusCode::kInvalidArgument, path + ": expected 9 numbers"};
  }
  return Status::ok();
}

namespace {

Homography compose_with_offset(const Homography& h, double dx, double dy) {
  // H * [1 0 dx; 0 1 dy; 0 0 1]
  Homography g = h;
  for (int r = 0; r < 3; ++r) g[r * 3 + 2] = h[r * 3 + 0] * dx + h[r * 3 + 1] * dy + h[r * 3 + 2];
  return g;
}

// An in-memory index viewed from 64-byte-aligned storage.
struct OwnedIndex {
  std::unique_ptr<std::uint8_t[]> storage;
  ModelIndex index;
  Status build(const cv::Mat& model, const Params& params) {
    std::vector<BuiltModel> models(1);
    Status s = build_model(model, "crop", params, models[0]);
    if (!s) return s;
    std::vector<std::uint8_t> bytes;
    s = serialize_index(models, params, bytes);
    if (!s) return s;
    storage.reset(new std::uint8_t[bytes.size() + 64]);
    const auto misalign = reinterpret_cast<std::uintptr_t>(storage.get()) % 64;
    std::uint8_t* aligned = storage.get() + (64 - misalign) % 64;
    std::memcpy(aligned, bytes.data(), bytes.size());
    return ModelIndex::view(aligned, bytes.size(), index);
  }
};

}  // namespace

Status evaluate_oxford(const OxfordEvalOptions& options, std::vector<OxfordCase>& cases,
                       void (*progress)(const OxfordCase&)) {
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
  bool run_keygraph = false;
  for (const std::string& m : options.methods) {
    BaselineOptions b;
    if (m == "keygraph") {
      run_keygraph = true;
    } else if (parse_baseline(m, b)) {
      baselines.emplace_back(b);
      baseline_methods.push_back(m);
    } else {
      return {StatusCode::kInvalidArgument, "unknown method '" + m + "'"};
    }
  }
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
      OwnedIndex owned;
      std::unique_ptr<DesktopDetector> detector;
      if (run_keygraph) {
        Status s = owned.build(crop, options.params);
        if (!s) return {s.code(), subsets[si] + " crop " + std::to_string(c) + ": " + s.message()};
        detector = std::make_unique<DesktopDetector>(owned.index);
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
          for (std::size_t m = 0; m < baselines.size() + (run_keygraph ? 1 : 0); ++m) {
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
            if (run_keygraph && m == baselines.size()) {
              r.method = "keygraph";
              DetectionList found;
              Status s = detector->detect(scene, found);
              r.time_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
              if (!s) return s;
              r.ransac_iterations = detector->stats().ransac_iterations;
              r.correspondences = detector->stats().correspondences;
              r.detected = !found.empty();
              if (r.detected) {
                r.inliers = found[0].inliers;
                found_h = found[0].homography;
              }
            } else {
              r.method = baseline_methods[m];
              baselines[m].detect(scene, r.detected, found_h, r.inliers);
              r.time_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
            }
            if (r.detected) {
              r.corner_error = 0;
              for (const Point2f& corner : outline) {
                const Point2f g = kg::apply(truth, corner);
                const Point2f d = kg::apply(found_h, corner);
                r.corner_error =
                    std::max(r.corner_error, std::hypot(double{g.x} - d.x, double{g.y} - d.y));
              }
            }
            cases.push_back(r);
            if (progress != nullptr) progress(r);
          }
        }
      }
    }
  }
  return Status::ok();
}

}  // namespace kg
