// Pipeline parameters: the settings of every step of Hashimoto & Cesar's
// "Object Detection Using Keygraphs" and of what keygraph adds to it. Every
// field is stored in the model index, so the scene side always processes
// frames exactly as the models were processed; these defaults are what
// `keygraph build` writes into a new index (`--set SECTION.FIELD=VALUE`
// changes one, e.g. `--set graph.min_distance=10`). An index is checked
// against the ranges below when it is written and when it is read.
//
// Each field says what it does, its unit and range, its default, and
// whether it is in the paper: "Paper: V" where the paper gives the value V,
// "Paper: no value" where it has the step but names no number, "Not in the
// paper" where the step is keygraph's own. Why each default is what it is,
// with the measurements: docs/RESULTS.md, "Why each default", and the
// sections named at each field.
#pragma once

#include <cstdint>

namespace kg {

// Paper: Hessian-Affine and MSER, each region's centroid taken as the
// keypoint.
enum class KeypointDetector : std::uint8_t {
  kHessian = 0,  // determinant of Hessian over scales (built into the core)
  kMser = 1,     // OpenCV MSER region centroids (desktop only: needs OpenCV)
};

// Keygraph structure: number of vertices of the circuit (paper Fig. 6).
enum class Structure : std::uint8_t {
  kArc = 2,       // two vertices, one arc
  kCircuit3 = 3,  // three-vertex circuit (paper's choice)
  kCircuit4 = 4,  // four-vertex circuit
};

struct KeypointParams {
  // Keypoint detector of the model images and the frames. Default kHessian,
  // the determinant of the Hessian over scales (Hessian-Affine's blobs
  // without its affine adaptation); kMser needs OpenCV, so an MSER index is
  // for the desktop detector only. Paper: both.
  KeypointDetector detector = KeypointDetector::kHessian;
  // Hessian detector: threshold on the scale-normalised determinant
  // sigma^4 det(H) of the image scaled to [0, 1]; >= 0. A blob of contrast A
  // peaks at A^2/16, so the default 0.0004 keeps blobs above a contrast of
  // about 0.08 (20 grey levels). Not in the paper (Hessian-Affine's own).
  // Keypoints it gives: docs/RESULTS.md, "Why each default".
  float hessian_threshold = 0.0004f;
  // Hessian detector: octaves of the Gaussian scale space, 1..8, and scale
  // levels per octave, 1..8. Defaults 4 and 3. Not in the paper.
  int hessian_octaves = 4;
  int hessian_levels = 3;  // scale levels per octave
  // Hessian detector: scale levels below the first octave's first (sigma
  // 1.6 px), each 2^(1/hessian_levels) finer, 0..hessian_levels: with 1,
  // maxima at 1.6 px too (the level below, 1.27 px, their neighbour); with
  // 3, down to 1.0 px. Their maxima must exceed hessian_fine_threshold (0:
  // hessian_threshold), as noise and texture peak there too. Both sides
  // use them (model views and frames). Defaults 1 and 0.0048: more signs
  // found at 60-160 px for 1.03x the frame's instructions; 3 finds about as
  // many on the sign sets and loses planar photos (docs/RESULTS.md, "Small
  // signs, scene side (issue 38)"). Files written before them hold 0: off,
  // as they were built. Not in the paper.
  int hessian_fine_levels = 1;
  float hessian_fine_threshold = 0.0048f;
  // MSER detector: OpenCV's delta (>= 1) and the smallest and largest
  // region in pixels (1 <= min <= max). Defaults 5, 30 and 14400: OpenCV's
  // defaults besides the area limits. Paper: MSER, no values.
  int mser_delta = 5;
  int mser_min_area = 30;
  int mser_max_area = 14400;
  // Without model views (ViewParams::min_size 0) only: the model image is
  // also detected at this many scales, each 1/sqrt(2) smaller than the last
  // (1, 1/sqrt2, 1/2 ...), with the keypoints mapped back to model pixels,
  // so scene instances smaller than the model still find their keypoints.
  // 1..8, default 3. With views, their scale pyramid does this. Not in the
  // paper.
  int model_scales = 3;
  // Without model views only: model keypoints closer than this, in model
  // pixels, are merged (the strongest kept). >= 0, default 2. Not in the
  // paper.
  float model_merge_distance = 2.0f;
  // Strongest keypoints kept per model image (per view with views); bounds
  // the model's arcs (about keypoints x neighbours). 4..32768, default 1500.
  // Not in the paper.
  int max_model_keypoints = 1500;
  // How the frame is searched: 1 as it is (the default); 2 upsampled 2x
  // (bilinear), the whole scene side (keypoints, arcs, descriptors, pose)
  // run on that and the poses mapped back to frame pixels; 3 both, keeping
  // the best of overlapping detections. Upsampled, the scene side's pixel
  // sizes (sampling distance, shortest arc, finest Hessian scale, inlier
  // threshold) count half a frame pixel, and the Detector reserves its
  // buffers for frames twice its Limits' width and height. 2 and 3 find
  // small signs in sharp low-resolution frames and lose signs near the
  // models' own size, which upsampled outgrow every model view, for several
  // times the frame's time: off by default (docs/RESULTS.md, "Upsampled
  // frames"). The model side is unchanged. Files written before it hold 0:
  // read as 1. With 3, stats() and last_matches()/last_keypoints() describe
  // the upsampled pass (the keypoint time and RANSAC iterations are summed
  // over both), and an overlapping detection of either pass wins by inliers,
  // which the upsampled frame has more of. Keypoints passed in by the caller
  // (MSER, SIFT vertex descriptors: DesktopDetector) are only mapped, not
  // found anew on the upsampled frame, so for those indexes the option
  // changes little but the pixel sizes. 4: the frame as it is, then
  // upsampled 2x only in one window of 112 frame pixels around the densest
  // cluster of keygraph correspondences of models the first pass found no
  // pose for (coarse to fine, issue 38; scene_upsample.cpp); not for
  // keypoints passed in. Not in the paper.
  int scene_upsample = 1;
};

// Descriptor of the keygraph vertices (paper section 6: SIFT). Off by
// default: the arcs' descriptors alone select correspondences.
enum class VertexDescriptor : std::uint8_t {
  kNone = 0,
  // SIFT (Lowe 2004) at each keypoint, 128 bytes: OpenCV's descriptor with
  // 8-bit output. Desktop only (OpenCV computes it): scene descriptors come
  // from the caller (Detector::detect with descriptors, or DesktopDetector).
  kSift = 1,
};
inline constexpr int kVertexDescriptorSize = 128;  // bytes per SIFT descriptor

// Order in which scene keypoints are offered to the Chebyshev sampler.
enum class SceneSampling : std::uint8_t {
  kRandom = 0,     // random maximal subset (paper)
  kStrongest = 1,  // strongest response first: repeatable across frames
};

struct GraphParams {
  // Vertices per keygraph (Structure): 2, 3 or 4. Default 3-circuits.
  // Paper: 3-circuits (2 and 4 also measured).
  Structure structure = Structure::kCircuit3;
  // Chebyshev distances in pixels, each > 0, min_distance <= max_distance.
  // min_distance: the shortest arc, of the model (in view pixels) and of the
  // scene; default 7, paper 10 (a small sign keeps enough keypoints and
  // arcs for several 3-circuits: docs/RESULTS.md, "Model views and small
  // signs"). max_distance: the longest model arc (scene arcs have no
  // maximum, as in the paper); default 100, paper 100. scene_sample_distance:
  // no two sampled scene keypoints closer than this; default 7, paper 10.
  float min_distance = 7.f;           // model arcs (in view pixels) and scene arcs
  float max_distance = 100.f;         // model arcs only
  float scene_sample_distance = 7.f;  // scene keypoint sampling
  // Order in which the scene keypoints are sampled (SceneSampling). Default
  // strongest first; paper: random (docs/RESULTS.md, "Why each default").
  SceneSampling scene_sampling = SceneSampling::kStrongest;
  // A keygraph correspondence is only selected when the affine map of its
  // first three vertices (model -> scene) has singular values whose ratio is
  // at most max_anisotropy and whose product (area scale) is within
  // [1/(2 s), 2 s] for s = RansacParams::max_scale_change. Arcs are checked
  // on their length ratio. 0 disables the check, otherwise >= 1; default
  // 2.5. Not in the paper (docs/RESULTS.md, "Why each default").
  float max_anisotropy = 2.5f;
  // An arc match is kept only when, at both of its ends, the scale change
  // the arc lengths imply (scene length / model length) agrees with the
  // keypoints' detector scales (scene sigma / model sigma) within this many
  // natural-log units. [0, 10], 0 disables the check (and 2.0 indexes, which
  // store no keypoint scales, never use it); default 0.7. Not in the paper
  // (docs/RESULTS.md, "Why each default").
  float max_scale_error = 0.7f;
  // Model arcs longer than this many detector scales (sigma) of either end
  // keypoint are not stored. >= 0, default 0: no limit. Frames rarely ask
  // for long arcs: a frame's Delaunay edges join near neighbours. Not in the
  // paper.
  float max_relative_length = 0.f;
  // In each model view, an arc a -> b is stored only when b is among the
  // max_neighbour_rank nearest keypoints of a within the arc range above,
  // or a among b's. A frame's arcs are Delaunay edges, which join near
  // neighbours, so arcs between far keypoints are rarely asked for, yet they
  // were most of a tilted index and crowded the search's leaves. >= 0,
  // 0: every pair in range (as the paper); default 24. Format 6.6; 0 in
  // older files. Not in the paper (docs/RESULTS.md, "Near-neighbour arcs").
  int max_neighbour_rank = 24;
  // A 3-circuit correspondence is also selected when only two of its arcs
  // were found by the search, provided the model holds the third arc
  // (between the two free ends) and its descriptor is within the similarity
  // threshold and scale box of the scene arc's, checked directly. The
  // search's budget is per query, so with many models in the index a sign's
  // arcs are crowded out of the leaves visited; two out of three suffice
  // then. Costs a per-keypoint arc table in the workspace and selection
  // time. 1: on (3-circuits only; no effect on other structures), 0: off
  // (and in files before format 6.5); default 1, with the tilted views, the
  // triangle check and the search budget (ViewParams::max_tilt). Not in the
  // paper (docs/RESULTS.md, "Circuit completion").
  int complete_circuits = 1;
};

// How arc descriptors are stored in the model index and compared at search
// time. The integer encodings store round(component * 32767) or
// round(component * 127) and compare integer squared distances against the
// similarity threshold scaled the same way; the scene descriptor is
// quantised identically before each query. float32 is the reference.
enum class DescriptorEncoding : std::uint8_t {
  kFloat32 = 0,  // 24 bytes per arc descriptor
  kInt16 = 1,    // 12 bytes
  kInt8 = 2,     // 6 bytes
};

struct DescriptorParams {
  // The arc descriptor (paper section 5): the image blurred by a Gaussian
  // of blur_sigma pixels ([0, 20], default 1; paper: a blur, no value); the
  // mean of three parallel Bresenham profiles parallel_offset pixels apart
  // (0..8, default 1; paper: one more profile on each side), resampled to
  // profile_length samples (4..256, default 30; paper 30); DFT coefficients
  // 1..coefficients kept (1..3 and 2 x coefficients < profile_length,
  // default 3; paper 3), divided by their norm.
  float blur_sigma = 1.0f;  // Gaussian blur before profiles
  int profile_length = 30;  // l: mean profile resampled to this length
  int coefficients = 3;     // m: DFT coefficients 1..m kept (<= kMaxCoefficients)
  int parallel_offset = 1;  // pixels between the three parallel profiles
  // 1: each profile sample taken at its exact place on the segment between
  // the keypoints' sub-pixel positions (bilinear, at 1/16 pixel, the
  // parallel profiles +-parallel_offset pixels perpendicular to the arc),
  // profile_length samples; 0: the paper's Bresenham lines between the
  // rounded endpoints. On an arc a few pixels long the rounding moves an
  // end by up to a tenth of the arc. Default 0 (off; older files hold 0);
  // docs/RESULTS.md "Short blurred arcs (issue 38)". Not in the paper.
  int subpixel_profiles = 0;
  // Euclidean distance under which two arc descriptors (unit vectors) are
  // similar: (0, 2], default 0.3; paper 0.5, which with dense keypoints lets
  // too many unrelated arcs through (docs/RESULTS.md, "Why each default").
  float similarity_threshold = 0.3f;
  // Paper section 7: a keygraph correspondence is also rejected when any
  // vertex pair is dissimilar (VertexDescriptor). Default kNone: off, the
  // arcs' descriptors alone select (docs/RESULTS.md, "Why each default").
  VertexDescriptor vertex_descriptor = VertexDescriptor::kNone;
  // Euclidean distance between the two SIFT descriptors, each scaled to
  // unit length (0 = same, sqrt(2) = orthogonal; an all-zero descriptor is
  // orthogonal to everything), above which vertices are dissimilar. (0, 2]
  // (0 allowed without vertex descriptors, which do not use it); default
  // 1.0. Paper: a threshold, no value (docs/RESULTS.md, "Why each
  // default").
  float vertex_threshold = 1.0f;
  // Storage and comparison of arc descriptors (DescriptorEncoding). Default
  // int8: the smallest index, and detection as good as float32's. Not in
  // the paper, which compares floats (docs/RESULTS.md, "Model index size").
  DescriptorEncoding encoding = DescriptorEncoding::kInt8;
  // The search visits at most this many leaves of the tree (up to 64 arcs
  // each), nearest first, and so finds the most similar model arcs but not
  // all of them. >= 0, 0 searches exactly; default 8 (the budget for an
  // index of up to search_reference_models models). Not in the paper, which
  // finds every similar arc (docs/RESULTS.md, "Why each default").
  int max_search_leaves = 8;
  // The budget above holds for an index of up to this many models and grows
  // with the square root of the models beyond it (at most 3-fold), so the
  // search keeps finding a sign's arcs as other models crowd the descriptor
  // space (the budget is per query, not per model). >= 0, 0 keeps the
  // budget fixed, as indexes before format 6.3 do; default 10. Not in the
  // paper (docs/RESULTS.md, "Index size and recall").
  int search_reference_models = 10;
};

struct RansacParams {
  // RANSAC over keygraph correspondences (paper section 7: an adaptive
  // iteration count with a cap; no values). confidence: P in (0, 1),
  // default 0.99. max_iterations: the cap, 1..10^7, default 5000.
  // inlier_threshold: reprojection error in scene pixels, > 0, default 4.
  // Not in the paper: min_inliers (>= 4, default 12) distinct keypoint
  // correspondences and min_inlier_keygraphs (>= 1, default 3) keygraph
  // correspondences fully inlier for a pose to count; max_scale_change
  // (>= 1, default 8), the largest model-to-scene area scale either way;
  // max_perspective (> 0, default 0.005), the largest |h31|, |h32| of the
  // homography normalised to the model's size.
  double confidence = 0.99;        // P in log(1-P)/log(1-p^h)
  int max_iterations = 5000;       // cap on iterations
  double inlier_threshold = 4.0;   // reprojection error in scene pixels
  int min_inliers = 12;            // distinct keypoint correspondences
  int min_inlier_keygraphs = 3;    // keygraph correspondences fully inlier
  double max_scale_change = 8.0;   // model-to-scene area scale, either way
  double max_perspective = 0.005;  // |h31|,|h32| after normalising to model size
  // Verification of a found pose. Under the final pose, the fraction of
  // model keypoints that land within inlier_threshold of a frame keypoint
  // must exceed the fraction for the pose shifted by three thresholds
  // (chance) by this many binomial standard deviations. >= 0, 0 turns the
  // verification off; default 4. Not in the paper (docs/RESULTS.md, "Why
  // the defaults differ from the paper's (ablation)").
  double min_verification_z = 4.0;
  // max_instances: RANSAC attempts, so instances found, per model and frame,
  // 1..64, default 4. seed: the RANSAC random state's seed, any value; fixed
  // so that a run repeats exactly. Neither is in the paper.
  int max_instances = 4;            // RANSAC attempts (so instances) per model and frame
  std::uint64_t seed = 0x6b657967;  // RANSAC random state, fixed for reproducibility
  // The smallest normalised cross-correlation between a model's stored
  // appearance (ViewParams::appearance_size), aligned onto the frame under
  // the pose, and the frame for a detection to be kept. [-1, 1] (measured
  // correlations are reported from 0 up, so a negative threshold acts as 0);
  // default 0.7. Format 6.2; 0 in older files. Not in the paper
  // (docs/RESULTS.md, "Appearance").
  float min_appearance = 0.7f;
  // A pose with less keypoint support than min_inliers and
  // min_verification_z ask is still kept when its appearance confirms it:
  // at least confirmed_min_inliers distinct inliers (0: never, otherwise
  // 4..100000; default 8), a verification z of confirmed_min_verification_z
  // ([0, 1000], default 2) and an appearance correlation of
  // confirmed_min_appearance ([-1, 1], default 0.8). Small and far signs
  // carry few keypoints but still look like themselves. Format 6.2; 0 in
  // older files. Not in the paper (docs/RESULTS.md, "Appearance").
  int confirmed_min_inliers = 8;
  float confirmed_min_verification_z = 2.f;
  float confirmed_min_appearance = 0.8f;
  // A keygraph correspondence of 3 or more vertices is dropped before RANSAC
  // when the triangle of its first three vertices, sampled in the model's
  // appearance and in the frame through the affine frame they define,
  // correlates below this (zero-mean normalised). [0, 1), 0 is off; default
  // 0.6, with the tilted views, whose extra correspondences it cleans
  // (ViewParams::max_tilt). Correspondences that cannot be judged (no
  // appearance, a tiny or flat triangle) are kept. Format 6.4; 0 (off) in
  // older files. Not in the paper (docs/RESULTS.md, "Triangle patch check").
  float min_triangle_correlation = 0.6f;
  // 1 orders each model's keygraph correspondences by how many keypoint
  // pairs they share with others and samples them progressively (PROSAC),
  // with PROSAC's stopping rule on prefixes holding 16 inlier
  // correspondences; 0 draws uniformly, as the paper does. Default 1.
  // Format 6.4; 0 (uniform draws) in older files, which keep their draws.
  // Not in the paper (docs/RESULTS.md, "Local optimisation, and progressive
  // sampling by default").
  int progressive_sampling = 1;
  // A small instance, whose found outline's longest side is at most
  // small_max_size frame pixels, is also kept with as few as
  // small_min_inliers distinct inliers (fewer than min_inliers and
  // confirmed_min_inliers ask) when its appearance correlates at least
  // small_min_appearance and its verification z reaches min_verification_z:
  // a 40-150 px sign gives a pose 5 to 10 keypoints, and its few inliers
  // need the appearance as independent evidence. small_max_size: [0,
  // 100000], 0 is off; default 150. small_min_inliers: 0 (off) or 4..100000,
  // default 6. small_min_appearance: [-1, 1], default 0.75. Format 6.10;
  // 0 (off) in older files. Not in the paper (docs/RESULTS.md,
  // "Small-instance verification (issue 38), 2026-12-06 fifth session").
  float small_max_size = 150.f;
  int small_min_inliers = 6;
  float small_min_appearance = 0.75f;
};

// Not in the paper: simulated views of each model, rendered by the builder
// (src/builder/model_views.h): the model image at every scale down to the
// smallest sign to be found and at out-of-plane tilts, each with its own
// keypoints, arcs and descriptors mapped back to model pixels. The paper's
// own paradigm (exhaustive on the model side, fast on the scene side): the
// frame's work does not grow with the views except through the search.
struct ViewParams {
  // Smallest long edge, in frame pixels, at which a model must still be
  // found: the views' scale pyramid stops there. [0, 100000], 0 disables
  // views (one model image; keypoints from KeypointParams::model_scales);
  // default 40 (docs/RESULTS.md, "Model views and small signs").
  float min_size = 40.f;
  // Each view's scale over the previous one's: [0.3, 0.95], default
  // 1/sqrt(2).
  float scale_step = 0.7071f;  // each view's scale over the previous one's
  // Largest size, relative to the model image, at which a model must still
  // be found: frontal views each 1 / scale_step larger than the last are
  // added up to it. [1, 4] and at most sqrt(RansacParams::max_scale_change)
  // (the pose check refuses the poses of larger views); 1: none, the
  // default. For models a camera sees larger than their image, such as a
  // whiteboard photographed from farther away than the frames; signs are
  // seen smaller than a model image of a few hundred pixels, and there
  // larger views cost detections (docs/RESULTS.md, "Views larger than the
  // model"). Format 6.7; older files read 1.
  float max_scale = 1.f;
  // Largest simulated out-of-plane rotation, degrees, [0, 80] (0: frontal
  // only), reached in tilt_levels steps (0..8) equally spaced in
  // t = 1 / cos(angle); longitudes 72 / t degrees apart (ASIFT's sampling).
  // Default 45 degrees in one level (t = 1.41 at 3 longitudes: 4 pyramids
  // with the frontal one), with the triangle check
  // (RansacParams::min_triangle_correlation), circuit completion
  // (GraphParams::complete_circuits) and the search budget
  // (DescriptorParams::max_search_leaves); ASIFT's 60 degrees in two levels
  // is the angled opt-in (docs/RESULTS.md, "Tilted views at 45 degrees by
  // default" and "Circuit completion").
  float max_tilt = 45.f;
  int tilt_levels = 1;
  // Keypoints of different views closer than this many view pixels (mapped
  // back to the model) are one model keypoint. [0, 10], default 1.5.
  float merge_distance = 1.5f;
  // An arc between the same two model keypoints is stored again for
  // another view only when its descriptor differs by more than this
  // (Euclidean) or its scale attributes by more than one grid step. [0, 2],
  // default 0.05.
  float dedupe_distance = 0.05f;
  // Long edge, in pixels, of the grey image of each model the index stores
  // (its appearance, format 6.2: the model image downsampled by area
  // averaging, never upsampled), which the detector aligns onto the frame
  // to refine and check a pose. 0 stores none (and files older than 6.2
  // read as 0), otherwise 16..512; default 128 (docs/RESULTS.md,
  // "Appearance").
  int appearance_size = 128;
  // Blurred small views (issue 38): every view whose long edge is at most
  // this many pixels is rendered a second time with a Gaussian blur of
  // kBlurredViewSigma view pixels on top of its anti-aliasing (a small
  // sign in a camera frame is blurrier than a sharp drawing of its size),
  // with its own keypoints and arcs, merged and deduplicated like any
  // other view's. [0, 100000], 0 is off (the default); 170 measured
  // (docs/RESULTS.md, "Blurred small views (issue 38)"). The builder's
  // alone: the frames are described as before. Format 6.11 (the first
  // field past 256 bytes of the parameter block); older files read 0.
  float blurred_max_size = 0.f;
  // Glowing small views (issue 38): every view whose long edge is at most
  // this many pixels is rendered a second time through a photometric model
  // of a small illuminated sign in a phone frame (highlights clipped, a
  // tone curve; src/builder/model_views.h, fitted on the real exit-sign dev
  // split), with its own keypoints and arcs, merged and deduplicated like
  // any other view's (after the blurred twin when both are on). [0,
  // 100000], 0 is off (the default); 170 measured (docs/RESULTS.md,
  // "Glowing small views (issue 38)"). The builder's alone: the frames are
  // described as before. Format 6.12; older files read 0.
  float glow_max_size = 0.f;
};

struct Params {
  KeypointParams keypoints;
  GraphParams graph;
  DescriptorParams descriptor;
  RansacParams ransac;
  ViewParams views;
};

}  // namespace kg
