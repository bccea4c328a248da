// The triangle patch check of the selected correspondences (not in the
// paper; RansacParams::min_triangle_correlation): each correspondence of 3
// or more vertices whose first triangle, sampled in the model's appearance
// and in the frame (core/selection/triangle_patch.h), correlates below the
// threshold is dropped before the pose; those that cannot be judged are
// kept.
#pragma once

#include "core/support/worker_pool.h"
#include "core/support/workspace.h"
#include "keygraph/detection.h"
#include "keygraph/image.h"
#include "keygraph/model_index.h"
#include "keygraph/params.h"

namespace kg {

// Measures each correspondence of `matches` (scene vertices index
// scene_points) on `blurred` (the frame as the descriptors saw it), records
// its correlation, and drops in place, keeping the order, those below
// params.ransac.min_triangle_correlation. Returns how many were dropped (0
// when the check is off or the structure has fewer than 3 vertices). With
// `workers` (nullptr: none) the correspondences are measured on them, each
// on its own: the same output for any thread count.
int check_triangle_patches(const ModelIndex& index, const Params& params, ImageView blurred,
                           const Point2f* scene_points, WorkVector<KeygraphMatch>& matches,
                           WorkerPool* workers = nullptr);

}  // namespace kg
