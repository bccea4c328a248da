// The pipelines users would pick instead of keygraphs, for side-by-side
// evaluation: OpenCV SIFT, ORB (2000 features) or AKAZE keypoints and
// descriptors, brute-force matching with Lowe's ratio test, and
// findHomography with RANSAC or USAC_MAGSAC. One thread each.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg {

enum class BaselineFeatures { kSift, kOrb, kAkaze };
enum class BaselineEstimator { kRansac, kMagsac };

struct BaselineOptions {
  BaselineFeatures features = BaselineFeatures::kSift;
  BaselineEstimator estimator = BaselineEstimator::kRansac;
  float ratio = 0.8f;  // Lowe's ratio test
  double reprojection_threshold = 3.0;
  int min_inliers = 10;  // a detection needs this many (find-object's default)
};

// "sift-ransac", "orb-magsac", ... ; false when the name is unknown.
bool parse_baseline(const std::string& name, BaselineOptions& out);
std::string baseline_name(const BaselineOptions& options);
std::vector<std::string> baseline_names();

class BaselineDetector {
 public:
  explicit BaselineDetector(const BaselineOptions& options);
  // Describes the model once.
  void set_model(const cv::Mat& gray);
  // Scene-side work: features, matching, homography. `found` is false when
  // fewer than min_inliers survive.
  void detect(const cv::Mat& scene, bool& found, Homography& h, int& inliers);

 private:
  BaselineOptions options_;
  cv::Ptr<cv::Feature2D> features_;
  cv::Ptr<cv::DescriptorMatcher> matcher_;
  std::vector<cv::KeyPoint> model_keypoints_;
  cv::Mat model_descriptors_;
};

}  // namespace kg
