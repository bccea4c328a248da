// The model quality report of `keygraph build` (stored in the index,
// format 6.1 sections 12-14; rated and printed by cli/device/quality_report.h):
// per model its views' keypoints, arcs and keygraphs, the smallest size in
// a frame at which it should still be found, how many of its arcs have a
// near-identical arc in another model, and which other models the real
// detector finds when the model is shown alone in a scene (look-alikes).
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "builder/index_writer.h"
#include "builder/model_builder.h"
#include "keygraph/params.h"
#include "keygraph/status.h"

namespace kg {

// A view carries enough to be found when it has this many times the
// keypoints and keygraphs that one detection needs (ransac.min_inliers,
// ransac.min_inlier_keygraphs): RANSAC needs inliers among the matches, and
// a frame never repeats every model keypoint.
inline constexpr int kViewKeypointFactor = 2;
inline constexpr int kViewKeygraphFactor = 5;

// Two arcs of different models are near-identical when their descriptors
// are closer than this (unit-norm descriptors, so 0..2) and their scale
// attributes are within the search's box: the default
// views.dedupe_distance, at which the builder treats two views'
// descriptions of one arc as the same arc. (Half the similarity threshold,
// 0.15, was measured too loose: about 90 % of every sign's arcs of the sign
// benchmark had such a neighbour; docs/QUALITY.md.)
inline constexpr float kNearIdenticalDistance = 0.05f;
// Arcs of a model searched for near-identical arcs of other models: at most
// this many, evenly spaced (exact for smaller models), the count scaled to
// all its arcs.
inline constexpr std::uint32_t kSharedSample = 8192;

struct QualityOptions {
  // Render each model as a scene and detect with the whole index (the
  // look-alike check); off, the report has no look-alikes (scene_size 0).
  bool look_alikes = true;
  // Long edge of the model in its scene, pixels (smaller models keep their
  // size), on a mid-grey background with a mild perspective.
  int scene_long_edge = 200;
  // Models measured at once (0: one per CPU the process may use); the
  // report is the same for any count.
  int threads = 0;
};

// Measures the report of `models`, built with `params` from `grays` (the
// model images, in the same order).
Status measure_quality(const std::vector<BuiltModel>& models, const std::vector<cv::Mat>& grays,
                       const Params& params, const QualityOptions& options, QualityReport& out);

// The scene of the look-alike check for one model image: the model at
// `long_edge` pixels, mildly tilted, on mid-grey. `outline` gets its four
// corners in the scene (clockwise from the top-left).
cv::Mat render_quality_scene(const cv::Mat& gray, int long_edge, cv::Point2f outline[4]);

// A picture of the model (keygraph build --draw-model): the image in grey,
// its keypoints as dots (a thin circle of their detector scale around),
// and its strongest keygraphs (3-circuits whose keypoints the most views
// detected, the larger first) in red to orange.
cv::Mat draw_model(const cv::Mat& gray, const BuiltModel& model, int max_keygraphs = 20);

}  // namespace kg
