// Models, scenes and reference poses from Debian's opencv-doc images that
// several detection tests and benchmarks share: the graf crop and its ground
// truth in graf3, the SIFT + RANSAC reference for box in box_in_scene, an
// index built in memory, and distractor models (tiles of unrelated photos).
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "builder/in_memory_index.h"
#include "builder/index_writer.h"
#include "builder/model_builder.h"
#include "builder/parallel.h"
#include "keygraph/detector.h"
#include "keygraph/model_index.h"
#include "support/test_data.h"

namespace kg::test {

// The graf model: a 300x300 crop of graf1.png at (200, 150).
constexpr int kGrafCropX = 200, kGrafCropY = 150, kGrafCropSize = 300;

inline cv::Mat graf_crop() {
  const cv::Mat graf1 = load_gray(opencv_data("graf1.png"));
  if (graf1.empty()) return {};
  return graf1(cv::Rect(kGrafCropX, kGrafCropY, kGrafCropSize, kGrafCropSize)).clone();
}

// Ground truth graf crop -> graf3: H1to3p * T(crop offset); all zero when
// the file cannot be read.
inline Homography graf_truth() {
  Homography out{};
  cv::FileStorage fs(opencv_data("H1to3p.xml"), cv::FileStorage::READ);
  cv::Mat h;
  fs["H13"] >> h;
  if (h.empty()) return out;
  h.convertTo(h, CV_64F);
  const cv::Mat t = (cv::Mat_<double>(3, 3) << 1, 0, kGrafCropX, 0, 1, kGrafCropY, 0, 0, 1);
  const cv::Mat g = h * t;
  for (int i = 0; i < 9; ++i) out[i] = g.at<double>(i / 3, i % 3);
  return out;
}

// Largest distance between a detection's corners and the model outline
// mapped by `truth`; infinity when a distance is not finite (a broken
// reference, e.g. the all-zero homography of a failed load, or corners at
// infinity), so that no tolerance test can pass on it.
inline double max_corner_error(const Detection& d, const Homography& truth, const ModelInfo& m) {
  double worst = 0.0;
  for (int c = 0; c < 4; ++c) {
    const Point2f g = kg::apply(truth, m.outline[c]);
    const double e = std::hypot(double{g.x} - d.corners[c].x, double{g.y} - d.corners[c].y);
    if (!std::isfinite(e)) return std::numeric_limits<double>::infinity();
    worst = std::max(worst, e);
  }
  return worst;
}

// Independent reference for box -> box_in_scene: SIFT, ratio test, RANSAC.
inline Homography sift_reference(const cv::Mat& model, const cv::Mat& scene) {
  cv::Ptr<cv::SIFT> sift = cv::SIFT::create();
  std::vector<cv::KeyPoint> km, ks;
  cv::Mat dm, ds;
  sift->detectAndCompute(model, cv::noArray(), km, dm);
  sift->detectAndCompute(scene, cv::noArray(), ks, ds);
  cv::BFMatcher matcher(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(dm, ds, knn, 2);
  std::vector<cv::Point2f> pm, ps;
  for (const auto& m : knn) {
    if (m.size() == 2 && m[0].distance < 0.7f * m[1].distance) {
      pm.push_back(km[m[0].queryIdx].pt);
      ps.push_back(ks[m[0].trainIdx].pt);
    }
  }
  Homography out{};
  if (pm.size() < 4) return out;
  cv::Mat h = cv::findHomography(pm, ps, cv::RANSAC, 3.0);
  if (h.empty()) return out;
  for (int i = 0; i < 9; ++i) out[i] = h.at<double>(i / 3, i % 3);
  return out;
}

// A model index serialised in memory and viewed from 64-byte aligned storage.
struct InMemoryIndex {
  std::unique_ptr<std::uint8_t[]> storage;
  std::size_t bytes = 0;
  ModelIndex index;
};

// box_in_scene.png resized by `scale` (area averaging), and the SIFT
// reference pose of box.png (`box`) in the full-size scene mapped into it;
// an empty image when the scene cannot be read.
struct ScaledScene {
  cv::Mat image;
  Homography truth{};
};
inline ScaledScene scaled_box_scene(const cv::Mat& box, double scale) {
  const cv::Mat full = load_gray(opencv_data("box_in_scene.png"));
  ScaledScene out;
  if (full.empty()) return out;
  cv::resize(full, out.image, cv::Size(), scale, scale, cv::INTER_AREA);
  const Homography h = sift_reference(box, full);
  // Pixel centres: x' = (x + 0.5) s - 0.5, taken exactly per axis.
  const double sx = static_cast<double>(out.image.cols) / full.cols;
  const double sy = static_cast<double>(out.image.rows) / full.rows;
  for (int c = 0; c < 3; ++c) {
    out.truth[c] = sx * h[c] + (0.5 * sx - 0.5) * h[6 + c];
    out.truth[3 + c] = sy * h[3 + c] + (0.5 * sy - 0.5) * h[6 + c];
    out.truth[6 + c] = h[6 + c];
  }
  return out;
}

inline Status view_in_memory(const std::vector<BuiltModel>& models, const Params& params,
                             InMemoryIndex& out) {
  std::vector<std::uint8_t> bytes;
  if (Status s = serialize_index(models, params, bytes); !s) return s;
  out.bytes = bytes.size();
  return view_aligned_copy(bytes, out.storage, out.index);
}

inline Status build_in_memory(const std::vector<std::pair<std::string, cv::Mat>>& images,
                              const Params& params, InMemoryIndex& out) {
  std::vector<BuiltModel> models(images.size());
  for (std::size_t i = 0; i < images.size(); ++i) {
    if (Status s = build_model(images[i].second, images[i].first, params, models[i]); !s) return s;
  }
  return view_in_memory(models, params, out);
}

// Up to `count` distractor model images: 240x240 tiles (row by row, at most
// 6 per photo, files in name order) of the opencv-doc photos other than
// box* and graf*, skipping near-flat tiles (grey-level standard deviation
// under 25). Named FILESTEM@X,Y.
inline std::vector<std::pair<std::string, cv::Mat>> distractor_tiles(std::size_t count) {
  constexpr int kTile = 240;
  constexpr int kPerPhoto = 6;
  std::vector<std::filesystem::path> files;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(KG_OPENCV_DATA_DIR, ec)) {
    const std::string name = entry.path().filename().string();
    const std::string ext = entry.path().extension().string();
    if ((ext == ".png" || ext == ".jpg") && name.rfind("box", 0) != 0 && name.rfind("graf", 0) != 0)
      files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<std::pair<std::string, cv::Mat>> out;
  for (const auto& file : files) {
    const cv::Mat image = load_gray(file.string());
    int taken = 0;
    for (int y = 0; y + kTile <= image.rows && taken < kPerPhoto; y += kTile) {
      for (int x = 0; x + kTile <= image.cols && taken < kPerPhoto; x += kTile) {
        if (out.size() >= count) return out;
        const cv::Mat tile = image(cv::Rect(x, y, kTile, kTile));
        cv::Scalar mean, stddev;
        cv::meanStdDev(tile, mean, stddev);
        if (stddev[0] < 25.0) continue;
        ++taken;
        out.emplace_back(file.stem().string() + "@" + std::to_string(x) + "," + std::to_string(y),
                         tile.clone());
      }
    }
  }
  return out;
}

// The first `count` distractor tiles the builder accepts (it refuses the
// few without keypoints, e.g. chessboard squares), built with `params`;
// fewer when the photos run out.
inline std::vector<BuiltModel> distractor_models(std::size_t count, const Params& params = {}) {
  // Built on every hardware thread: the first `count` tiles that build, in
  // tile order, whatever the thread count. The threads stop handing out
  // tiles once `count` have built (every tile before the last handed out
  // has run); any tile still needed is built after them.
  const std::vector<std::pair<std::string, cv::Mat>> tiles = distractor_tiles(count + 40);
  std::vector<BuiltModel> built(tiles.size());
  std::vector<char> ran(tiles.size(), 0), ok(tiles.size(), 0);
  std::atomic<std::size_t> successes{0};
  auto build = [&](std::size_t i) {
    ok[i] = build_model(tiles[i].second, tiles[i].first, params, built[i]).is_ok() ? 1 : 0;
    ran[i] = 1;
    return ok[i] != 0;
  };
  parallel_for(tiles.size(), 0,
               [&](std::size_t i) { return !build(i) || successes.fetch_add(1) + 1 < count; });
  std::vector<BuiltModel> out;
  for (std::size_t i = 0; i < tiles.size() && out.size() < count; ++i) {
    if (!ran[i]) build(i);
    if (ok[i]) out.push_back(std::move(built[i]));
  }
  return out;
}

}  // namespace kg::test
