// Homography estimation from point correspondences: normalised DLT,
// Levenberg-Marquardt refinement of the reprojection error, and the
// plausibility test that rejects degenerate poses.
// Convention: scene = H * model (see keygraph/types.h).
#pragma once

#include "keygraph/params.h"
#include "keygraph/types.h"

namespace kg {

// Least-squares homography from n >= 4 correspondences (Hartley
// normalisation, SVD of the DLT system). Returns false when the points are
// degenerate (collinear triples in a minimal set, coincident points) or the
// result is not finite. The result is scaled so that h[8] == 1 when possible.
bool fit_homography(const Point2f* model, const Point2f* scene, int n, Homography& h);

// Levenberg-Marquardt on the 8 free parameters (h[8] fixed to 1), minimising
// sum |scene_i - H(model_i)|^2. Never returns a result with a larger error
// than the input. Returns the final RMS reprojection error in pixels.
double refine_homography(const Point2f* model, const Point2f* scene, int n, Homography& h,
                         int max_iterations = 20);

// Root mean square reprojection error of H over the correspondences.
double rms_reprojection_error(const Point2f* model, const Point2f* scene, int n,
                              const Homography& h);

// Whether H is a plausible pose of a planar model of the given size:
// - the model rectangle maps to a convex quadrilateral with the same
//   orientation (no mirroring, no fold-over, w > 0 at every corner);
// - area scale between 1/max_scale_change^2... precisely: the mapped area over
//   the model area lies in [1/max_scale_change, max_scale_change];
// - no side of the mapped quadrilateral shorter than 4 px (collapse);
// - the perspective terms, expressed for the model normalised to unit size,
//   |h31 * w|, |h32 * h| (with H scaled so h33 = 1) below max_perspective * max(w,h).
bool is_plausible_pose(const Homography& h, float model_width, float model_height,
                       const RansacParams& params);

}  // namespace kg
