// Detections that explain the same part of the frame: look-alike signs, one
// sign explained by two models, or one instance found twice.
#pragma once

#include "keygraph/detection.h"
#include "keygraph/types.h"

namespace kg {

// Whether two detections' outlines cover the same part of the frame: the
// centre of either lies inside the other.
bool outlines_overlap(const Point2f* a, const Point2f* b);
// Whether each outline's centre lies inside the other (a stricter overlap).
bool outlines_hold_each_other(const Point2f* a, const Point2f* b);

// Where detections overlap, keeps the best supported one: the clearly
// better appearance correlation where both have one, else the most inliers,
// then the largest score over chance. Keeps the order of the rest.
void keep_best_of_overlapping(DetectionList& found);

}  // namespace kg
