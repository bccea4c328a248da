// Simulated views of a model image (the model side of DESIGN.md's "beyond
// the paper"): the image as a camera would see it at smaller sizes and
// under out-of-plane rotations, rendered offline so that the frame's work
// does not change. Each view is an affine map from model pixels to view
// pixels: a rotation by the tilt's longitude, a squeeze by the tilt factor
// t = 1 / cos(tilt) across that direction, and a uniform scale, as ASIFT
// simulates affine cameras (here for the model only). Views are rendered
// with anti-aliasing (a Gaussian pre-blur matched to each axis' shrink).
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "keygraph/params.h"
#include "keygraph/status.h"

namespace kg {

struct ModelView {
  double scale = 1.0;      // uniform scale, view pixels per model pixel (before the tilt)
  double tilt = 1.0;       // t = 1 / cos(theta) >= 1
  double longitude = 0.0;  // direction of the tilt, degrees in [0, 180)
  cv::Matx23d to_view;     // model pixel centre -> view pixel centre
  cv::Size size;           // view image size
  // Extra Gaussian blur, view pixels, after the view is rendered (0: none):
  // the blurred twin of a small view (ViewParams::blurred_max_size).
  double blur = 0.0;
  // The glowing twin of a small view (ViewParams::glow_max_size): the view
  // rendered through the glow model below after its anti-aliasing.
  bool glow = false;
};

// The blur of a small view's blurred twin, in view pixels: what a sign of
// that size in a phone or synthetic frame adds to a sharp drawing
// (measured on the tuning sets: 1.5 px on views up to 170 px found 5 more
// signs than 1.0 px on views up to 120 px, which lost two over 160 px;
// docs/RESULTS.md, "Blurred small views (issue 38)").
inline constexpr double kBlurredViewSigma = 1.5;

// The photometric model of a small illuminated sign in a phone frame
// (ViewParams::glow_max_size), on intensities in [0, 1]: the highlights
// clipped at kGlowClip (rescaled to [0, 1]), then a tone curve
// y^kGlowGamma. Fitted on the real exit-sign dev split (50 signs): the
// model image warped by each truth pose and rendered through a model,
// against the frame's pixels inside the sign, 1 - their correlation,
// median over the signs: 0.42 for the sharp view, 0.40 for this one. The
// grid also had a bloom (the part above a threshold blurred by 1.5-6 px and
// added back 0.3-1.5 times) and a camera blur (0.5-2.5 px): the fit set
// both to 0, and a bloom of gain 1 and 2 px with a 0.75 px blur predicted
// the frames worse (0.48) (docs/RESULTS.md, "Glowing small views (issue
// 38)").
inline constexpr double kGlowClip = 0.7;
inline constexpr double kGlowGamma = 1.3;

// That model as a table of the 256 grey levels: round(255 * (min(v / 255,
// kGlowClip) / kGlowClip)^kGlowGamma).
cv::Mat glow_table();

// The views of a width x height model for `params`, in this order: the
// frontal scale pyramid (scale 1, then each params.scale_step smaller until
// the long edge reaches params.min_size), and for each tilt level the same
// pyramid at longitudes 72 / t degrees apart, then the frontal views larger
// than the model image (each 1 / params.scale_step larger, up to
// params.max_scale). Each view of the pyramids whose long edge is at most
// params.blurred_max_size is followed by its blurred twin (the same map,
// blur kBlurredViewSigma), and each view whose long edge is at most
// params.glow_max_size by its glowing twin (glow set), after the blurred
// one. With views disabled
// (min_size == 0) the frontal pyramid of `legacy_scales` levels, each
// 1/sqrt(2) smaller.
std::vector<ModelView> model_views(int width, int height, const ViewParams& params,
                                   int legacy_scales);

// The most pixels a tilted view's canvas may take: the view, or the
// rotated model image it is squeezed from (render_view()), at most 16 times
// the model's own pixels or kMinViewCanvasBound, whichever is more. A model
// at most about 30 times longer than it is wide stays within it at any
// longitude (a square one takes twice its pixels at 45 degrees); a strip
// such as 16384 x 16 would take 134 million pixels at 45 degrees, for
// minutes and gigabytes.
inline constexpr double kViewCanvasFactor = 16.0;
inline constexpr double kMinViewCanvasBound = 16777216.0;

// An error naming the size when a tilted view of a width x height model
// would take more than the bound above (the model is then refused, with
// what to do instead); ok otherwise, and for any model without tilted views.
Status check_view_canvas(int width, int height, const ViewParams& params);

// Renders `view` of `gray` (8-bit), with pixels outside the model taken
// from its nearest border (no edges that a wall behind a sign would not
// show), blurred by view.blur when that is set, through the glow model
// (glow_table()) when view.glow is. `inside` gets 255 where the
// view shows model pixels.
void render_view(const cv::Mat& gray, const ModelView& view, cv::Mat& out, cv::Mat& inside);

// Tilt levels for views up to `max_tilt` degrees in steps of about 0.5 in
// t = 1 / cos(angle), as ASIFT's tilts: 1 level to about 55 degrees
// (45: t = 1.41), 2 to about 62 (60: t = 1.5 and 2), at least 1 and at
// most 8.
int asift_tilt_levels(float max_tilt);

}  // namespace kg
