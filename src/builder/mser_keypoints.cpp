#include <algorithm>
#include <cmath>

#include <opencv2/features2d.hpp>

#include "builder/image_io.h"
#include "builder/keypoints.h"

namespace kg {

void mser_keypoints(const cv::Mat& gray, const KeypointParams& params, std::vector<Keypoint>& out) {
  out.clear();
  cv::Ptr<cv::MSER> mser =
      cv::MSER::create(params.mser_delta, params.mser_min_area, params.mser_max_area);
  std::vector<std::vector<cv::Point>> regions;
  std::vector<cv::Rect> boxes;
  mser->detectRegions(gray, regions, boxes);
  for (const auto& region : regions) {
    if (region.empty()) continue;
    double sx = 0, sy = 0;
    for (const cv::Point& p : region) {
      sx += p.x;
      sy += p.y;
    }
    const double n = static_cast<double>(region.size());
    Keypoint k;
    k.x = static_cast<float>(sx / n);
    k.y = static_cast<float>(sy / n);
    k.scale = static_cast<float>(std::sqrt(n / 3.14159265358979));
    // Smaller regions are localised better; rank them first.
    k.response = static_cast<float>(1.0 / n);
    out.push_back(k);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const Keypoint& a, const Keypoint& b) { return a.response > b.response; });
}

void KeypointExtractor::extract(const cv::Mat& gray, const KeypointParams& params,
                                int max_keypoints, std::vector<Keypoint>& out) {
  if (params.detector == KeypointDetector::kMser) {
    mser_keypoints(gray, params, out);
    if (static_cast<int>(out.size()) > max_keypoints)
      out.resize(static_cast<std::size_t>(max_keypoints));
    return;
  }
  hessian_.detect(view_of(gray), params, max_keypoints, out);
}

}  // namespace kg
