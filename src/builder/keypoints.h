// Keypoints of a whole image with the detector an index names: the core's
// Hessian detector, or OpenCV's MSER (region centroids) on the desktop.
// Model building and desktop detection both go through here, so model and
// scene keypoints always come from the same code.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "core/keypoints/hessian.h"
#include "keygraph/params.h"
#include "keygraph/types.h"

namespace kg {

class KeypointExtractor {
 public:
  // Strongest first, at most max_keypoints.
  void extract(const cv::Mat& gray, const KeypointParams& params, int max_keypoints,
               std::vector<Keypoint>& out);

 private:
  HessianDetector hessian_;
};

// MSER region centroids; response = region area stability proxy (smaller
// regions first is not meaningful, so response is the region's size rank).
void mser_keypoints(const cv::Mat& gray, const KeypointParams& params, std::vector<Keypoint>& out);

}  // namespace kg
