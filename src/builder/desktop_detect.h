// Detection on a desktop image: the core detector, with OpenCV computing
// the keypoints when the index was built with a detector the core lacks,
// and the keypoints' SIFT descriptors when the index has vertex descriptors.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "builder/detector_settings.h"
#include "builder/keypoints.h"
#include "builder/sift_descriptors.h"
#include "keygraph/detector.h"

namespace kg {

class DesktopDetector {
 public:
  explicit DesktopDetector(const ModelIndex& index, const Limits& limits = Limits{})
      : detector_(index, limits), limits_(limits) {}
  // With `settings` applied; a setting that does not apply is the status
  // detect() returns.
  DesktopDetector(const ModelIndex& index, const Limits& limits, const DetectorSettings& settings);
  Status detect(const cv::Mat& gray, DetectionList& out);
  const DetectStats& stats() const { return detector_.stats(); }
  Detector& core() { return detector_; }

 private:
  Detector detector_;
  Limits limits_;
  Status settings_status_;
  KeypointExtractor extractor_;
  std::vector<Keypoint> keypoints_;
  SiftDescriber sift_;
  std::vector<std::uint8_t> vertex_descriptors_;
};

}  // namespace kg
