// Frames upsampled 2x before detection (KeypointParams::scene_upsample 2,
// or 3 for the frame and its upsampled copy): the pipeline runs on the
// upsampled frame and its results are mapped back to frame pixels here.
#include <algorithm>

#include "core/image/upsample.h"
#include "core/pipeline/frame_pipeline.h"
#include "core/pose/confidence.h"

namespace kg {

ImageView FramePipeline::work_frame(ImageView frame) {
  if (!upsampling()) return frame;
  upsample2x(frame, upsampled_);
  return view_of(upsampled_);
}

void FramePipeline::upsample_keypoints(const Keypoint*& keypoints, int& count,
                                       const std::uint8_t*& descriptors) {
  if (count > limits_.max_keypoints) {
    keep_strongest(keypoints, count, descriptors);
    if (descriptors != nullptr) descriptors = detected_descriptors_.data();
  } else {
    detected_.assign(keypoints, keypoints + count);
  }
  for (Keypoint& k : detected_) {
    k.x = to_upsampled(k.x);
    k.y = to_upsampled(k.y);
    k.scale *= 2.f;
  }
  keypoints = detected_.data();
  count = static_cast<int>(detected_.size());
}

void FramePipeline::map_to_frame(DetectionList& out) {
  for (Detection& d : out) {
    d.homography = homography_from_upsampled(d.homography);
    for (Point2f& c : d.corners) c = {from_upsampled(c.x), from_upsampled(c.y)};
    d.rms_error *= 0.5;
    // From the mapped support (the inliers stay those of the upsampled
    // frame's keypoints: the model was fitted on frames as they are).
    d.confidence = detection_confidence(d);
  }
  for (Keypoint& k : scene_keypoints_) {
    k.x = from_upsampled(k.x);
    k.y = from_upsampled(k.y);
    k.scale *= 0.5f;
  }
}

void FramePipeline::merge(const DetectionList& more, DetectionList& out) {
  for (const Detection& d : more) {
    if (!out.push_back(d)) stats_.truncated_detections = true;
  }
  keep_best_of_overlapping(out);
  // Each pass kept up to max_detections; together they may not exceed it.
  // The least supported go first (fewer inliers, then the smaller score
  // over chance, then the later one), in place: no allocation.
  const auto most = static_cast<std::size_t>(limits_.max_detections);
  while (out.size() > most) {
    std::size_t worst = 0;
    for (std::size_t i = 1; i < out.size(); ++i) {
      const Detection& a = out[i];
      const Detection& w = out[worst];
      if (a.inliers < w.inliers ||
          (a.inliers == w.inliers && a.score - a.chance <= w.score - w.chance))
        worst = i;
    }
    for (std::size_t i = worst; i + 1 < out.size(); ++i) out[i] = out[i + 1];
    out.truncate(out.size() - 1);
    stats_.truncated_detections = true;
  }
}

}  // namespace kg
