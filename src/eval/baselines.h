// The pipelines users would pick instead of keygraphs, for side-by-side
// evaluation: OpenCV SIFT, ORB (2000 features) or AKAZE keypoints and
// descriptors, brute-force matching with Lowe's ratio test, and
// findHomography with RANSAC or USAC_MAGSAC.
//
// Several models at once, as a user of ORB + RANSAC would find an index of
// N signs: the scene's features are computed once per frame, then every
// model's descriptors are matched against them (2 nearest neighbours, ratio
// test) and, with enough matches, its homography estimated. Callers that
// measure time call cv::setNumThreads(1) first (the evaluations do), so
// every method runs on one thread.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg {

// The largest image (width x height) the baselines take, model or scene:
// OpenCV's SIFT builds its pyramid from the image upsampled 2x in float, so
// a 4096 x 4096 scene takes 3.9 GB (AKAZE's scale space is not far behind).
// At 4 megapixels SIFT stays near 1 GB; the real photo sets' largest image
// is 2.3 megapixels. Evaluations refuse larger images with
// over_baseline_limit()'s reason instead of running out of memory.
inline constexpr long long kMaxBaselinePixels = 1LL << 22;
// "4096x4096 is over the 4194304 pixels the OpenCV baselines take (...)".
std::string over_baseline_limit(int width, int height);

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
// The methods of a comma-separated --methods list, "all" standing for
// keygraph and every baseline.
std::vector<std::string> method_list(const std::string& comma_separated);

// One model found in a frame.
struct BaselineDetection {
  int model_id = -1;        // index into the models given to set_models()
  Homography homography{};  // model pixels -> scene pixels
  Point2f corners[4];       // model outline (pixel centres, clockwise from top-left) mapped
  int matches = 0;          // ratio-test survivors for this model
  int inliers = 0;          // of those, findHomography's inliers
};

// What the last detect() did, for benchmarks and reports.
struct BaselineStats {
  int scene_keypoints = 0;
  long long matches = 0;     // ratio-test survivors, summed over models
  int homographies = 0;      // findHomography calls
  double ms_features = 0;    // scene keypoints and descriptors
  double ms_match = 0;       // matching and ratio test, all models
  double ms_homography = 0;  // findHomography, all models
};

class BaselineDetector {
 public:
  explicit BaselineDetector(const BaselineOptions& options);
  const BaselineOptions& options() const { return options_; }

  // Describes the models once (8-bit gray), replacing any earlier ones;
  // model i gets id i. A model without features is kept and never found.
  void set_models(const std::vector<cv::Mat>& grays);
  void set_model(const cv::Mat& gray) { set_models({gray}); }
  int model_count() const { return static_cast<int>(models_.size()); }
  int model_keypoints(int model_id) const;

  // Scene-side work for every model. Clears and fills `out` with the
  // models that reach min_inliers (at most one instance each), in model
  // order.
  void detect(const cv::Mat& scene, std::vector<BaselineDetection>& out);
  // The first model only: `found` is false when it is not detected.
  void detect(const cv::Mat& scene, bool& found, Homography& h, int& inliers);

  const BaselineStats& stats() const { return stats_; }

 private:
  struct Model {
    int width = 0, height = 0;
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
  };
  BaselineOptions options_;
  cv::Ptr<cv::Feature2D> features_;
  cv::Ptr<cv::DescriptorMatcher> matcher_;
  std::vector<Model> models_;
  BaselineStats stats_;
  // Per-frame storage, reused.
  std::vector<cv::KeyPoint> scene_keypoints_;
  cv::Mat scene_descriptors_;
  std::vector<std::vector<cv::DMatch>> knn_;
  std::vector<cv::Point2f> model_points_, scene_points_;
  std::vector<BaselineDetection> found_;
};

}  // namespace kg
