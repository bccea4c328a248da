// The model quality report as `keygraph build` and `keygraph inspect` print
// it, from the report stored in the index (format 6.1 sections 12-14;
// measured by builder/model_quality.h): a star rating per model with the
// reasons, a warning line per weak or confusable model, and a rating of the
// index. No OpenCV: the device build's inspect uses it. Thresholds and how
// they were chosen: docs/QUALITY.md.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "keygraph/model_index.h"

namespace kg::cli {

// A model found only when its long edge in the frame is above this many
// pixels (a quarter of a 640-pixel frame's width) loses a star, above
// twice this another one.
inline constexpr float kLargeOnlySize = 150.f;
// More than this fraction of a model's arcs near-identical to other
// models' arcs: low distinctiveness, one star less. On the sign benchmark's
// 50 signs the fraction ranges from 16 % to 72 %, median 31 %; the signs
// above half are the simple ones (arrows, single symbols).
inline constexpr double kMaxSharedFraction = 0.5;

struct ModelRating {
  int stars = 0;                      // 0..5
  const char* grade = "weak";         // good (4-5), fair (2-3), weak (0-1)
  std::vector<std::string> warnings;  // one reason each; empty for a sound model
};

// Model m's rating (the index must have a quality report).
ModelRating rate_model(const ModelIndex& index, int m);

// Prints the report to `out`: a line per model (with its views when
// `with_views`), the warnings, and the index's rating. Prints one line
// saying there is none when the index has no report.
void print_quality_report(const ModelIndex& index, bool with_views, std::FILE* out);

}  // namespace kg::cli
