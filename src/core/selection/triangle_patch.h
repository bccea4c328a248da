// A discriminative check of a keygraph correspondence (issue 14, lever 1):
// three corresponding vertices define an affine frame, so the triangle they
// span (enlarged about its centroid, to take in some texture around it)
// sampled at fixed barycentric points in the model's stored appearance and
// in the frame gives two patch vectors that an affine warp of the plane
// leaves equal. Their zero-mean normalised correlation tells a right
// correspondence (high) from one whose arcs matched by chance (low), before
// RANSAC ever sees it. Fixed-size sample arrays on the stack: no allocation.
#pragma once

#include "keygraph/image.h"
#include "keygraph/model_index.h"
#include "keygraph/types.h"

namespace kg {

struct TrianglePatch {
  // False when the correlation cannot be judged: no appearance or frame,
  // a triangle degenerate or too small in either image, too few samples
  // inside both images, or a flat patch. A caller keeps such matches.
  bool measured = false;
  float correlation = 0.f;  // zero-mean normalised, in [-1, 1], when measured
};

// Barycentric sample points per triangle (a lattice of 9 steps per edge).
inline constexpr int kTriangleSamples = 55;

// The correlation of the triangle model[0..3) (model pixels) in
// `appearance` with the triangle scene[0..3) (frame pixels) in `frame`
// (best the lightly blurred frame). Whichever image is finer at the
// triangle is averaged over the other's pixel footprint so that the two
// sample at the same resolution.
TrianglePatch triangle_patch_correlation(const ModelAppearance& appearance, ImageView frame,
                                         const Point2f* model, const Point2f* scene);

}  // namespace kg
