#include "build/oxford.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>

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
  Rng rng(options.seed);
  for (const std::string& subset : subsets) {
    const std::string dir = options.dataset + "/" + subset;
    cv::Mat img1;
    Status s = load_gray(dir + "/img1.png", img1);
    if (!s) return s;
    const int size = options.crop_size;
    if (img1.cols < size || img1.rows < size)
      return {StatusCode::kInvalidArgument, dir + "/img1.png smaller than the crop size"};
    std::vector<cv::Mat> scenes(7);
    std::vector<Homography> truths(7);
    for (int n = 2; n <= 6; ++n) {
      s = load_gray(dir + "/img" + std::to_string(n) + ".png", scenes[n]);
      if (!s) return s;
      s = read_homography(dir + "/H1to" + std::to_string(n) + "p", truths[n]);
      if (!s) return s;
    }
    const int crops = options.centre_crop ? 1 : options.crops_per_subset;
    for (int c = 0; c < crops; ++c) {
      int x = (img1.cols - size) / 2, y = (img1.rows - size) / 2;
      if (!options.centre_crop) {
        x = static_cast<int>(rng.uniform(static_cast<std::uint32_t>(img1.cols - size + 1)));
        y = static_cast<int>(rng.uniform(static_cast<std::uint32_t>(img1.rows - size + 1)));
      }
      OwnedIndex owned;
      s = owned.build(img1(cv::Rect(x, y, size, size)).clone(), options.params);
      if (!s) return {s.code(), subset + " crop " + std::to_string(c) + ": " + s.message()};
      DesktopDetector detector(owned.index);
      const ModelInfo model = owned.index.model(0);
      for (int n = 2; n <= 6; ++n) {
        OxfordCase r;
        r.subset = subset;
        r.crop = c;
        r.crop_x = x;
        r.crop_y = y;
        r.degree = n;
        DetectionList found;
        const auto start = std::chrono::steady_clock::now();
        s = detector.detect(scenes[n], found);
        r.time_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        if (!s) return s;
        r.ransac_iterations = detector.stats().ransac_iterations;
        r.correspondences = detector.stats().correspondences;
        if (!found.empty()) {
          const Homography truth = compose_with_offset(truths[n], x, y);
          r.detected = true;
          r.inliers = found[0].inliers;
          r.corner_error = 0;
          for (const Point2f& corner : model.outline) {
            const Point2f g = kg::apply(truth, corner);
            const Point2f d = kg::apply(found[0].homography, corner);
            r.corner_error =
                std::max(r.corner_error, std::hypot(double{g.x} - d.x, double{g.y} - d.y));
          }
        }
        cases.push_back(r);
        if (progress != nullptr) progress(r);
      }
    }
  }
  return Status::ok();
}

}  // namespace kg
