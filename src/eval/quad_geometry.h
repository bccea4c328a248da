// Geometry for scoring detections against hand-made ground truth: corner
// errors that do not depend on the order the corners were clicked in, and
// the intersection over union of two quadrilaterals (convex or not).
// OpenCV-free, so that the manifest fuzzer can link it.
#pragma once

#include "keygraph/types.h"

namespace kg {

// The largest corner distance of the best pairing of a's corners with b's
// over the 4 cyclic shifts in both directions (8 pairings): the score does
// not depend on which corner a person clicked first, nor on the direction.
double order_free_corner_error(const Point2f (&a)[4], const Point2f (&b)[4]);

// Signed area (shoelace): positive when counter-clockwise in y-up axes.
double signed_area(const Point2f (&q)[4]);

// A simple (not self-intersecting) quadrilateral of positive area; convex
// or not. Bow-ties, repeated or collinear corners are not.
bool is_simple_quad(const Point2f (&q)[4]);

// Area of the intersection over the area of the union. 0 when either
// quadrilateral is not simple (a degenerate detection overlaps nothing).
double quad_iou(const Point2f (&a)[4], const Point2f (&b)[4]);

// The longest of the four sides, pixels.
double longest_side(const Point2f (&q)[4]);

// `h` divided by h33: false (and `h` unspecified) unless it is finite and
// invertible before and after (h33 = 0, or so near 0 that the division
// overflows, is not).
bool normalise_homography(Homography& h);

}  // namespace kg
