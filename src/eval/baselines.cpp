#include "eval/baselines.h"

#include <algorithm>
#include <chrono>
#include <sstream>

#include <opencv2/calib3d.hpp>

namespace kg {

std::string over_baseline_limit(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height) + " is over the " +
         std::to_string(kMaxBaselinePixels) +
         " pixels the OpenCV baselines take (SIFT alone would need gigabytes): downscale it, or "
         "use the keygraph methods only (--methods keygraph)";
}

bool parse_baseline(const std::string& name, BaselineOptions& out) {
  const std::size_t dash = name.find('-');
  if (dash == std::string::npos) return false;
  const std::string f = name.substr(0, dash), e = name.substr(dash + 1);
  if (f == "sift") {
    out.features = BaselineFeatures::kSift;
  } else if (f == "orb") {
    out.features = BaselineFeatures::kOrb;
  } else if (f == "akaze") {
    out.features = BaselineFeatures::kAkaze;
  } else {
    return false;
  }
  if (e == "ransac") {
    out.estimator = BaselineEstimator::kRansac;
  } else if (e == "magsac") {
    out.estimator = BaselineEstimator::kMagsac;
  } else {
    return false;
  }
  return true;
}

std::string baseline_name(const BaselineOptions& o) {
  const char* f = o.features == BaselineFeatures::kSift  ? "sift"
                  : o.features == BaselineFeatures::kOrb ? "orb"
                                                         : "akaze";
  return std::string(f) + (o.estimator == BaselineEstimator::kRansac ? "-ransac" : "-magsac");
}

std::vector<std::string> method_list(const std::string& comma_separated) {
  std::vector<std::string> out;
  std::stringstream in(comma_separated);
  for (std::string m; std::getline(in, m, ',');) {
    if (m != "all") {
      out.push_back(m);
      continue;
    }
    out.push_back("keygraph");
    for (const std::string& b : baseline_names()) out.push_back(b);
  }
  return out;
}

std::vector<std::string> baseline_names() {
  return {"sift-ransac", "sift-magsac", "orb-ransac", "orb-magsac", "akaze-ransac", "akaze-magsac"};
}

BaselineDetector::BaselineDetector(const BaselineOptions& options) : options_(options) {
  switch (options.features) {
    case BaselineFeatures::kSift:
      features_ = cv::SIFT::create();
      matcher_ = cv::BFMatcher::create(cv::NORM_L2);
      break;
    case BaselineFeatures::kOrb:
      features_ = cv::ORB::create(2000);
      matcher_ = cv::BFMatcher::create(cv::NORM_HAMMING);
      break;
    case BaselineFeatures::kAkaze:
      features_ = cv::AKAZE::create();
      matcher_ = cv::BFMatcher::create(cv::NORM_HAMMING);
      break;
  }
}

void BaselineDetector::set_models(const std::vector<cv::Mat>& grays) {
  models_.assign(grays.size(), Model{});
  for (std::size_t i = 0; i < grays.size(); ++i) {
    Model& m = models_[i];
    m.width = grays[i].cols;
    m.height = grays[i].rows;
    if (!grays[i].empty())
      features_->detectAndCompute(grays[i], cv::noArray(), m.keypoints, m.descriptors);
  }
}

int BaselineDetector::model_keypoints(int model_id) const {
  if (model_id < 0 || model_id >= model_count()) return 0;
  return static_cast<int>(models_[static_cast<std::size_t>(model_id)].keypoints.size());
}

void BaselineDetector::detect(const cv::Mat& scene, std::vector<BaselineDetection>& out) {
  using Clock = std::chrono::steady_clock;
  const auto ms = [](Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
  };
  out.clear();
  stats_ = BaselineStats{};
  auto t0 = Clock::now();
  scene_keypoints_.clear();
  features_->detectAndCompute(scene, cv::noArray(), scene_keypoints_, scene_descriptors_);
  stats_.scene_keypoints = static_cast<int>(scene_keypoints_.size());
  stats_.ms_features = ms(t0, Clock::now());
  if (scene_descriptors_.rows < 2) return;
  const int method =
      options_.estimator == BaselineEstimator::kRansac ? cv::RANSAC : cv::USAC_MAGSAC;
  for (std::size_t id = 0; id < models_.size(); ++id) {
    const Model& model = models_[id];
    if (model.descriptors.empty()) continue;
    t0 = Clock::now();
    knn_.clear();
    matcher_->knnMatch(model.descriptors, scene_descriptors_, knn_, 2);
    model_points_.clear();
    scene_points_.clear();
    for (const auto& m : knn_) {
      if (m.size() == 2 && m[0].distance < options_.ratio * m[1].distance) {
        model_points_.push_back(model.keypoints[static_cast<std::size_t>(m[0].queryIdx)].pt);
        scene_points_.push_back(scene_keypoints_[static_cast<std::size_t>(m[0].trainIdx)].pt);
      }
    }
    const auto t1 = Clock::now();
    stats_.ms_match += ms(t0, t1);
    stats_.matches += static_cast<long long>(model_points_.size());
    if (static_cast<int>(model_points_.size()) < std::max(4, options_.min_inliers)) continue;
    cv::Mat mask;
    const cv::Mat hm = cv::findHomography(model_points_, scene_points_, method,
                                          options_.reprojection_threshold, mask);
    ++stats_.homographies;
    stats_.ms_homography += ms(t1, Clock::now());
    if (hm.empty()) continue;
    BaselineDetection d;
    d.model_id = static_cast<int>(id);
    d.matches = static_cast<int>(model_points_.size());
    d.inliers = cv::countNonZero(mask);
    if (d.inliers < options_.min_inliers) continue;
    for (int i = 0; i < 9; ++i)
      d.homography[static_cast<std::size_t>(i)] = hm.at<double>(i / 3, i % 3);
    const float w = static_cast<float>(model.width - 1), h = static_cast<float>(model.height - 1);
    const Point2f outline[4] = {{0.f, 0.f}, {w, 0.f}, {w, h}, {0.f, h}};
    for (int c = 0; c < 4; ++c) d.corners[c] = kg::apply(d.homography, outline[c]);
    out.push_back(d);
  }
}

void BaselineDetector::detect(const cv::Mat& scene, bool& found, Homography& h, int& inliers) {
  detect(scene, found_);
  found = false;
  inliers = 0;
  for (const BaselineDetection& d : found_) {
    if (d.model_id != 0) continue;
    found = true;
    h = d.homography;
    inliers = d.inliers;
  }
}

}  // namespace kg
