// SIFT vertex descriptors (paper section 6; Lowe 2004) at given keypoints,
// for VertexDescriptor::kSift. Model building and desktop detection both go
// through here, so model and scene vertices are described alike.
//
// OpenCV computes the descriptor (cv::SIFT with 8-bit output: the 4x4x8
// gradient histogram normalised to unit length, clipped at 0.2,
// renormalised, times 512, rounded and saturated to 0..255) from its own
// Gaussian pyramid level nearest the keypoint's scale. OpenCV uses the angle
// of provided keypoints as given, so the orientation is assigned here the
// way SIFT assigns it (dominant peak of the 36-bin gradient orientation
// histogram around the keypoint, on the same pyramid level): the
// descriptors are rotation invariant.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "keygraph/params.h"
#include "keygraph/types.h"

namespace kg {

// Keypoint::scale is a blob sigma in pixels, the quantity SIFT's own
// keypoints carry as size / 2; keypoints without a scale (0) are described
// at this sigma.
inline constexpr float kSiftDefaultSigma = 6.f;

class SiftDescriber {
 public:
  SiftDescriber();
  // Resizes `out` to count * kVertexDescriptorSize bytes: row i describes
  // keypoints[i] in the 8-bit image `gray`.
  void describe(const cv::Mat& gray, const Keypoint* keypoints, int count,
                std::vector<std::uint8_t>& out);

 private:
  cv::Ptr<cv::SIFT> sift_;
  std::vector<cv::Mat> pyramid_;  // octave * kLayers + layer, float
  std::vector<cv::KeyPoint> cv_keypoints_;
  cv::Mat descriptors_;
};

}  // namespace kg
