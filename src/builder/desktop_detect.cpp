#include "builder/desktop_detect.h"

#include <algorithm>

#include "builder/image_io.h"
#include "platform/files/frame_limits.h"

namespace kg {

namespace {

Limits with_threads(Limits limits, int threads) {
  limits.threads = threads;
  return limits;
}

}  // namespace

DesktopDetector::DesktopDetector(const ModelIndex& index, const Limits& limits,
                                 const DetectorSettings& settings)
    : detector_(index, with_threads(limits, settings.threads)),
      limits_(with_threads(limits, settings.threads)) {
  DetectOptions options = DetectOptions::from(index);
  for (const std::string& a : settings.options) {
    const std::size_t eq = a.find('=');
    if (eq == std::string::npos) {
      settings_status_ = {StatusCode::kInvalidArgument, "not NAME=VALUE: " + a};
      return;
    }
    settings_status_ = set_detect_option(options, std::string_view(a).substr(0, eq),
                                         std::string_view(a).substr(eq + 1));
    if (!settings_status_) return;
  }
  if (!settings.options.empty()) settings_status_ = detector_.set_options(options);
}

Status DesktopDetector::detect(const cv::Mat& gray, DetectionList& out) {
  if (!settings_status_) return settings_status_;
  // Desktop frames come in any size: grow the core's workspace to fit
  // (by the frame, never to the product of two thin frames' sides), with
  // the options set on core() kept.
  const Limits& current = detector_.limits();
  if (gray.cols > current.max_width || gray.rows > current.max_height)
    detector_ =
        Detector(detector_.index(), platform::limits_for_frame(current, gray.cols, gray.rows),
                 detector_.options());
  const Params& params = detector_.index().params();
  if (params.descriptor.vertex_descriptor == VertexDescriptor::kSift) {
    if (gray.empty() || gray.type() != CV_8UC1)
      return {StatusCode::kInvalidArgument, "empty or malformed frame (8-bit gray expected)"};
    // The keypoints the core's detect(frame) would find (for Hessian), found
    // here so that they can be described.
    extractor_.extract(gray, params.keypoints, limits_.max_keypoints, keypoints_);
    const int count = static_cast<int>(keypoints_.size());
    sift_.describe(gray, keypoints_.data(), count, vertex_descriptors_);
    return detector_.detect(view_of(gray), keypoints_.data(), count, vertex_descriptors_.data(),
                            out);
  }
  if (params.keypoints.detector == KeypointDetector::kHessian)
    return detector_.detect(view_of(gray), out);
  extractor_.extract(gray, params.keypoints, limits_.max_keypoints, keypoints_);
  return detector_.detect(view_of(gray), keypoints_.data(), static_cast<int>(keypoints_.size()),
                          out);
}

}  // namespace kg
