// Tables of keygraph repeatability: per subset, per degree (img2..img6)
// and overall, as text and CSV (eval/repeatability.h measures).
#pragma once

#include <string>
#include <vector>

#include "eval/repeatability.h"

namespace kg {

// Counts and times pooled over a set of cases and detections.
struct RepeatabilityTally {
  PairRepeatability counts;  // summed
  int pairs = 0;
  int images = 0;
  long long keypoints = 0;  // summed over images
  long long pixels = 0;
  double ms = 0;

  double repeatability() const;               // model_repeated / model_inside
  double chance() const;                      // the same for the shifted projection
  double keypoints_per_image() const;         // over every image detected (img1..img6)
  double sampled_per_image() const;           // scene images
  double sampled_repeatability() const;       // sampled_repeated / sampled_inside
  double sampled_chance() const;              // the same shifted
  double triangles_repeated() const;          // fraction of triangles in view
  double triangles_keygraph() const;          // fraction of triangles in view
  double keygraphs_per_image() const;         // triangles_keygraph per scene image
  double chance_keygraphs_per_image() const;  // triangles_keygraph_shifted per scene image
  double ms_per_image() const;
  double ms_per_megapixel() const;
};

// Pools the cases and timings whose detector is `detector` and, when not
// empty, whose subset is `subset`; degree 0 takes every degree (timings
// ignore the degree).
RepeatabilityTally tally_repeatability(const std::vector<RepeatabilityCase>& cases,
                                       const std::vector<DetectionTiming>& timings,
                                       const std::string& detector, const std::string& subset,
                                       int degree);

// One table per subset (repeatability per degree, keypoints and keygraph
// triangles per image) and an overall one (everything).
std::string repeatability_text(const std::vector<RepeatabilityCase>& cases,
                               const std::vector<DetectionTiming>& timings,
                               const RepeatabilityOptions& options);

// One line per case, with the detection times of img1 and the scene.
std::string repeatability_csv(const std::vector<RepeatabilityCase>& cases,
                              const std::vector<DetectionTiming>& timings);

}  // namespace kg
