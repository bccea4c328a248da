// Homography estimation from point correspondences: normalised DLT,
// Levenberg-Marquardt refinement of the reprojection error, and the
// plausibility test that rejects degenerate poses.
// Convention: scene = H * model (see keygraph/types.h).
#pragma once

#include "keygraph/params.h"
#include "keygraph/types.h"

namespace kg {

// Least-squares homography from n >= 4 correspondences (Hartley
// normalisation of both sets; n == 4: the 8x8 DLT system with h33 = 1,
// n > 4 or a singular 8x8: the smallest eigenvector of the 9x9 A^T A).
// Returns false when the points are degenerate or the result is not
// finite. Degenerate: non-finite or all coincident points; for n == 4, any
// three model or scene points within 1e-2 (twice the triangle area, in
// coordinates normalised to mean centroid distance sqrt(2)) of collinear,
// which includes coincident pairs; for n > 4, all points on one line or a
// DLT null space of more than one dimension. The result is scaled so that
// h[8] == 1, or to unit norm when |h[8]| is tiny.
bool fit_homography(const Point2f* model, const Point2f* scene, int n, Homography& h);

// fit_homography for RANSAC hypotheses. For n > 4 it first solves the
// least squares with h33 = 1 in normalised coordinates (LDLT of the 8x8
// normal equations, about a tenth of the eigen solver's cost, which was
// most of the pose stage), and uses fit_homography's null-space fit only
// when those equations are ill conditioned. Equal to fit_homography for
// exact correspondences; on noisy ones a different algebraic fit, as
// good (tested). Not for a homography mapping the points' centroid near
// infinity (never a plausible pose): h33 = 1 cannot represent it, and the
// result is then a poor fit that the caller's scoring rejects.
bool fit_homography_hypothesis(const Point2f* model, const Point2f* scene, int n, Homography& h);

// Levenberg-Marquardt on the 8 free parameters (scale fixed by h33 = 1 in
// Hartley-normalised coordinates, for conditioning), minimising
// sum |scene_i - H(model_i)|^2. Never returns a result with a larger error
// than the input: h is left untouched unless the RMS error drops (also when
// n < 4 or the input maps a point to infinity). The result has h[8] == 1.
// Returns the RMS reprojection error in pixels of the returned h.
double refine_homography(const Point2f* model, const Point2f* scene, int n, Homography& h,
                         int max_iterations = 20);

// Root mean square reprojection error of H over the correspondences.
double rms_reprojection_error(const Point2f* model, const Point2f* scene, int n,
                              const Homography& h);

// Whether H is a plausible pose of a planar model of size w x h, the model
// rectangle having corners (0,0), (w,0), (w,h), (0,h). With H finite and
// scaled so that h33 = 1 (a tiny |h33|, the origin at infinity, fails):
// - w > 0 at every corner (nothing behind the camera, no fold-over);
// - the mapped corners form a convex quadrilateral with the model's
//   orientation: every turn has the model rectangle's sign (no mirroring);
// - the mapped area over the model area lies in
//   [min(1/max_scale_change, min_area), max_scale_change] (min_area: the
//   smallest area scale the model's views cover, smallest_area_scale());
// - no side of the mapped quadrilateral shorter than 4 px (collapse);
// - perspective: the change of w along each model side is bounded,
//   |h31| * w <= max_perspective * max(w, h) and
//   |h32| * h <= max_perspective * max(w, h).
bool is_plausible_pose(const Homography& h, float model_width, float model_height,
                       const RansacParams& params, double min_area);
// The smallest area scale (instance area over model area) at which a model
// of this size is to be found: the views reach views.min_size on the long
// edge (with a margin of 1.5 for the frame's own keypoint scales); without
// views, 1 / ransac.max_scale_change. Views only ever widen the lower
// bound, and only for models large enough to need it.
double smallest_area_scale(const Params& params, float model_width, float model_height);
bool is_plausible_pose(const Homography& h, float model_width, float model_height,
                       const RansacParams& params);

}  // namespace kg
