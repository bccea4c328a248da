#include "build/baselines.h"

#include <opencv2/calib3d.hpp>

namespace kg {

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

void BaselineDetector::set_model(const cv::Mat& gray) {
  model_keypoints_.clear();
  features_->detectAndCompute(gray, cv::noArray(), model_keypoints_, model_descriptors_);
}

void BaselineDetector::detect(const cv::Mat& scene, bool& found, Homography& h, int& inliers) {
  found = false;
  inliers = 0;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  features_->detectAndCompute(scene, cv::noArray(), keypoints, descriptors);
  if (model_descriptors_.empty() || descriptors.rows < 2) return;
  std::vector<std::vector<cv::DMatch>> knn;
  matcher_->knnMatch(model_descriptors_, descriptors, knn, 2);
  std::vector<cv::Point2f> model_points, scene_points;
  for (const auto& m : knn) {
    if (m.size() == 2 && m[0].distance < options_.ratio * m[1].distance) {
      model_points.push_back(model_keypoints_[m[0].queryIdx].pt);
      scene_points.push_back(keypoints[m[0].trainIdx].pt);
    }
  }
  if (static_cast<int>(model_points.size()) < std::max(4, options_.min_inliers)) return;
  cv::Mat mask;
  const int method =
      options_.estimator == BaselineEstimator::kRansac ? cv::RANSAC : cv::USAC_MAGSAC;
  const cv::Mat hm =
      cv::findHomography(model_points, scene_points, method, options_.reprojection_threshold, mask);
  if (hm.empty()) return;
  inliers = cv::countNonZero(mask);
  if (inliers < options_.min_inliers) return;
  for (int i = 0; i < 9; ++i) h[i] = hm.at<double>(i / 3, i % 3);
  found = true;
}

}  // namespace kg
