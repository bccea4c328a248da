// A detection's confidence: the estimated probability that it is right (the
// right model, every corner within 10 px of the truth), from the support
// the pose estimator measured. A logistic model, fitted offline on the sign
// benchmark's tuning frames (docs/RESULTS.md, "Detection confidence"), so that a user
// can threshold one number instead of four.
#pragma once

#include <algorithm>
#include <cmath>

#include "keygraph/detector.h"

namespace kg {

// Coefficients of logit(P(right)) = bias + sum of weight * feature.
struct ConfidenceModel {
  double bias;
  double log_inliers;        // log(distinct inlier keypoints)
  double inlier_keygraphs;   // min(keygraphs all inlier, 50) / 10
  double verification_z;     // min(z, 40) / 10
  double score_over_chance;  // score - chance
  double rms_error;          // pixels
  double appearance;         // Detection::appearance (normalised cross-correlation)
};

// Both fitted by docs/fit-confidence.py on the detections of the sign
// benchmark's tuning set: seed 1, 300 frames, indexes of 1, 10 and 50 signs
// (`keygraph synth -o SIGNS --seed 1 --signs 50 --frames 300`, then
// `keygraph eval --synth SIGNS --methods keygraph --out OUT`).
//
// kConfidenceModel, for detections with an appearance correlation (indexes
// of format 6.2): fitted with the appearance gates off
// (`--set ransac.min_appearance=0 --set ransac.confirmed_min_appearance=0`,
// 460 detections, 422 right), so that it also saw the poses the gates
// remove; the correlation carries it. The verification z-score is left out
// (weight 0): with the support above chance beside it, its fitted weight
// came out negative.
inline constexpr ConfidenceModel kConfidenceModel = {-11.4715, 1.6673,  0.5090, 0.0,
                                                     2.1110,   -1.1113, 12.1473};
// kConfidenceModelNoAppearance, for detections without one (indexes of
// format 6.0 and 6.1, or a pose with most of the model outside the frame):
// fitted on an index without appearances (`--set views.appearance_size=0`,
// 344 detections, 310 right); the support above chance and the number of
// inliers carry it.
inline constexpr ConfidenceModel kConfidenceModelNoAppearance = {-5.3556, 1.7664,  -0.0354, -0.0491,
                                                                 8.0887,  -0.7759, 0.0};

inline double detection_confidence(const Detection& d, const ConfidenceModel& m) {
  const double logit = m.bias + m.log_inliers * std::log(std::max(1, d.inliers)) +
                       m.inlier_keygraphs * std::min(d.inlier_keygraphs, 50) / 10.0 +
                       m.verification_z * std::min(d.verification_z, 40.0) / 10.0 +
                       m.score_over_chance * (d.score - d.chance) + m.rms_error * d.rms_error +
                       m.appearance * std::max(d.appearance, -1.0);
  return 1.0 / (1.0 + std::exp(-logit));
}

// The model that fits what the detection measured.
inline double detection_confidence(const Detection& d) {
  return detection_confidence(
      d, d.appearance >= 0.0 ? kConfidenceModel : kConfidenceModelNoAppearance);
}

}  // namespace kg
