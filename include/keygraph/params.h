// Pipeline parameters. Defaults are the paper's values (Hashimoto & Cesar,
// "Object Detection Using Keygraphs") where the paper gives one, except
// where a measurement on the Oxford set chose otherwise; those fields say
// so, with the paper's value (docs/RESULTS.md has the numbers). Every field
// is stored in the model index, so the scene side always processes frames
// exactly as the models were processed.
#pragma once

#include <cstdint>

namespace kg {

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
  KeypointDetector detector = KeypointDetector::kHessian;
  // Hessian detector: relative threshold on the scale-normalised
  // determinant (images normalised to [0,1]; a blob of contrast A peaks at
  // A^2/16, so this keeps blobs above ~0.08, 20 gray levels). Gives about
  // 550-1850 keypoints on typical 640x480 photos (opencv-doc, Oxford).
  float hessian_threshold = 0.0004f;
  int hessian_octaves = 4;
  int hessian_levels = 3;  // scale levels per octave
  // MSER (OpenCV defaults besides the area limits).
  int mser_delta = 5;
  int mser_min_area = 30;
  int mser_max_area = 14400;
  // Model images are also processed at these scales (1, 1/sqrt2, 1/2 ...)
  // and the keypoints mapped back, so scene instances smaller than the model
  // still find their keypoints. Count of scales, each 1/sqrt(2) smaller.
  int model_scales = 3;
  // Model keypoints closer than this (pixels) are merged.
  float model_merge_distance = 2.0f;
  // Strongest model keypoints kept per model (bounds arcs: ~n * neighbours).
  int max_model_keypoints = 1500;
  // Not in the paper: 1 searches the frame as it is; 2 upsamples it 2x
  // (bilinear) and runs the whole scene side (keypoints, arcs, descriptors,
  // pose) on that, mapping poses back to frame pixels; 3 does both and keeps
  // the best of overlapping detections. Upsampled, the scene side's pixel
  // sizes (sampling distance, shortest arc, finest Hessian scale, inlier
  // threshold) count half a frame pixel, and the Detector reserves its
  // buffers for frames twice its Limits' width and height. The upsampled
  // pass finds small signs in sharp low-resolution frames (the sign
  // benchmark downsampled to 320x240, seed 2: 26 % found, 40 % upsampled,
  // 45 % both) and loses signs near the models' own size, which upsampled
  // outgrow every model view (640x480, 50 signs: 51.7 % -> 32.5 %; Oxford
  // crops 77 % -> 38 %). Off by default: 2.8x the frame's time upsampled,
  // 3.9x for both (docs/RESULTS.md, "Upsampled frames"). The model side is
  // unchanged. Files written before it hold 0: read as 1. With 3, stats()
  // and last_matches()/last_keypoints() describe the upsampled pass (the
  // keypoint time and RANSAC iterations are summed over both), and an
  // overlapping detection of either pass wins by inliers, which the
  // upsampled frame has more of. Keypoints passed in by the caller (MSER,
  // SIFT vertex descriptors: DesktopDetector) are only mapped, not found
  // anew on the upsampled frame, so for those indexes the option changes
  // little but the pixel sizes.
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
  Structure structure = Structure::kCircuit3;
  // Chebyshev distances, pixels. Paper: 10, 100 and 10. The shorter minimum
  // arc and sampling distance (7) let a small sign carry enough keypoints
  // and arcs for several 3-circuits; with model views, on the project's
  // sign benchmark (seed 1, 100 frames, one sign in the index) they find
  // 51.3 % of the signs within 10 px against 46.2 % at 10, with as few
  // false detections (docs/RESULTS.md, "Model views and small signs").
  float min_distance = 7.f;           // model arcs (in view pixels) and scene arcs
  float max_distance = 100.f;         // model arcs only
  float scene_sample_distance = 7.f;  // scene keypoint sampling
  // Paper: random. Strongest-first finds 27 of 40 Oxford centre crops within
  // 5 px with no wrong pose, random 23 with 2 wrong (docs/RESULTS.md).
  SceneSampling scene_sampling = SceneSampling::kStrongest;
  // Not in the paper: a keygraph correspondence is only selected when the
  // affine map of its first three vertices (model -> scene) has singular
  // values whose ratio is at most max_anisotropy and whose product (area
  // scale) is within [1/(2 s), 2 s] for s = RansacParams::max_scale_change.
  // Arcs are checked on their length ratio. 0 disables the check. Without
  // it, 18 of 40 Oxford centre crops are found within 5 px (2 wrong poses);
  // with 2.5, 27 (none wrong).
  float max_anisotropy = 2.5f;
  // Not in the paper: an arc match is kept only when, at both of its ends,
  // the scale change the arc lengths imply (scene length / model length)
  // agrees with the keypoints' detector scales (scene sigma / model sigma)
  // within this many natural-log units. 0 disables the check (and 2.0
  // indexes, which store no keypoint scales, never use it). The Hessian
  // scale of a re-detected keypoint is within 0.35 of the true scale change
  // for about 90 % of them on Oxford img2 and img4. At 0.7 about 20 % of the
  // arc matches survive and the correct keygraph correspondences nearly all
  // do (graf img2: 156 of 157); Oxford centre crops: 67.5 % within 3 px
  // against 60.0 % without the check, 75.0 % against 70.0 % within 10 px,
  // no wrong pose (docs/RESULTS.md).
  float max_scale_error = 0.7f;
  // Not in the paper: model arcs longer than this many detector scales
  // (sigma) of either end keypoint are not stored (0: no limit). Frames
  // rarely ask for them: a frame's Delaunay edges join near neighbours.
  float max_relative_length = 0.f;
  // Not in the paper: in each model view, an arc a -> b is stored only when
  // b is among the max_neighbour_rank nearest keypoints of a within the arc
  // range above, or a among b's (0: every pair in range). A frame's arcs are
  // Delaunay edges, which join near neighbours, so arcs between far
  // keypoints are rarely asked for, yet they were most of a tilted index and
  // crowded the search's leaves. At 24 the ten models of bench_frame take
  // 8.2 MB instead of 31.7, and with 8 leaves instead of 10 the sign
  // benchmark's tuning seed finds as many signs (docs/RESULTS.md, "Near-
  // neighbour arcs"). Format 6.6; 0 in older files.
  int max_neighbour_rank = 24;
  // Not in the paper: a 3-circuit correspondence is also selected when only
  // two of its arcs were found by the search, provided the model holds the
  // third arc (between the two free ends) and its descriptor is within the
  // similarity threshold and scale box of the scene arc's, checked directly.
  // The search's budget is per query, so with many models in the index a
  // sign's arcs are crowded out of the leaves visited; two out of three
  // suffice then. Costs a per-keypoint arc table in the workspace (8.25
  // bytes per model arc, at most 136 per keypoint) and about 3x the
  // selection's time. 1: on (3-circuits only; no effect on other
  // structures), 0: off (and in files before format 6.5). On by default
  // since the 45-degree views, with the check and then 10 leaves
  // (ViewParams; 8 since near-neighbour arcs): see there for what they do
  // together.
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
  float blur_sigma = 1.0f;  // Gaussian blur before profiles
  int profile_length = 30;  // l: mean profile resampled to this length
  int coefficients = 3;     // m: DFT coefficients 1..m kept (<= kMaxCoefficients)
  int parallel_offset = 1;  // pixels between the three parallel profiles
  // Euclidean distance under which two arc descriptors are similar. Paper:
  // 0.5. With dense keypoints 0.5 lets 1.3 % of unrelated arcs through and
  // correct keygraph correspondences drown (2 of 40 Oxford centre crops
  // found within 5 px, 4 wrong poses); 0.3 keeps 82 % of true arcs and
  // 0.2 % of unrelated ones (27 of 40, none wrong; docs/RESULTS.md).
  float similarity_threshold = 0.3f;
  // Paper section 7: a keygraph correspondence is also rejected when any
  // vertex pair is dissimilar. Off by default: on the Oxford centre crops it
  // finds 27 of 40 within 5 px at vertex_threshold 1.0 with one wrong pose,
  // against 26 and none without (measured at commit 85a601f).
  VertexDescriptor vertex_descriptor = VertexDescriptor::kNone;
  // Euclidean distance between the two SIFT descriptors, each scaled to
  // unit length (0 = same, sqrt(2) = orthogonal; an all-zero descriptor is
  // orthogonal to everything), above which vertices are dissimilar. Unrelated
  // SIFT vectors lie near 1.05 (non-negative entries). Measured on
  // graf1 -> graf3 and box -> box_in_scene: 1.0 keeps 84 % and 76 % of true
  // vertex pairs and 35 % of unrelated ones; 0.7 keeps 70 % and 51 % against
  // 0.8 %, and the box in box_in_scene is then lost: a keygraph needs all
  // its vertices similar (tests/core/test_vertex_descriptor.cpp).
  float vertex_threshold = 1.0f;
  // Storage and comparison of arc descriptors (see DescriptorEncoding).
  // int8 (not in the paper, which compares floats): 15 bytes per model arc
  // against 41 in float32, and detection as good. Oxford, 10 seeded crops per
  // subset (400 cases): 57.2 % within 3 px, 67.0 % within 10 px, 3 wrong
  // poses, against float32's 56.8 %, 66.8 % and 6 (int16: 56.5 %, 67.0 %,
  // 3); centre crops (40): 70.0 %, 72.5 %, none wrong, as float32
  // (docs/RESULTS.md, "Model index size").
  DescriptorEncoding encoding = DescriptorEncoding::kInt8;
  // Not in the paper: the search visits at most this many leaves of the
  // tree (up to 64 arcs each), nearest first, and so finds the most similar
  // model arcs but not all of them; 0 searches exactly. 20 leaves of 64
  // scan more arcs than 32 of 32 (the format 4 default) for less than
  // half the tree walking: Oxford 400 crops 56.5 % / 67.0 %, 3 wrong,
  // against 56.5 % / 66.5 %, 5 wrong, exact (docs/RESULTS.md, "Detection
  // on the Oxford set"; docs/RUNTIME.md, "Frame benchmark"). 10 since the
  // tilted views and circuit completion are on (ViewParams): completion
  // needs two of a circuit's three arcs from the search, not three, and
  // 10 leaves found as much as 20 for less time (docs/RESULTS.md, "Circuit
  // completion"). 8 since model arcs join near neighbours only
  // (GraphParams::max_neighbour_rank): the smaller index's leaves hold
  // more of what frames ask for (docs/RESULTS.md, "Near-neighbour arcs").
  int max_search_leaves = 8;
  // Not in the paper: the budget above holds for an index of up to this
  // many models and grows with the square root of the models beyond it
  // (at most 8-fold), so the search keeps finding a sign's arcs as other
  // models crowd the descriptor space (the budget is per query, not per
  // model); 0 keeps the budget fixed, as indexes before format 6.3 do.
  // Sign benchmark, 50 signs (45 leaves): 51.7 % -> 64.6 % found within
  // 10 px on the held-out seed, as many as with ten (docs/RESULTS.md,
  // "Index size and recall").
  int search_reference_models = 10;
};

struct RansacParams {
  double confidence = 0.99;        // P in log(1-P)/log(1-p^h)
  int max_iterations = 5000;       // cap on iterations
  double inlier_threshold = 4.0;   // reprojection error in scene pixels
  int min_inliers = 12;            // distinct keypoint correspondences
  int min_inlier_keygraphs = 3;    // keygraph correspondences fully inlier
  double max_scale_change = 8.0;   // model-to-scene area scale, either way
  double max_perspective = 0.005;  // |h31|,|h32| after normalising to model size
  // Not in the paper: verification of a found pose. Under the final pose,
  // the fraction of model keypoints that land within inlier_threshold of a
  // frame keypoint must exceed the fraction for the pose shifted by three
  // thresholds (chance) by this many binomial standard deviations.
  double min_verification_z = 4.0;
  int max_instances = 4;            // RANSAC attempts (so instances) per model and frame
  std::uint64_t seed = 0x6b657967;  // RANSAC random state, fixed for reproducibility
  // Not in the paper: the smallest normalised cross-correlation, in [-1, 1],
  // between a model's stored appearance (ViewParams::appearance_size),
  // aligned onto the frame under the pose, and the frame for a detection to
  // be kept (measured correlations are reported from 0 up, so a negative
  // threshold acts as 0). Format 6.2; 0 in older files. 0.7 keeps the sign benchmark's
  // detection rate above what it was without appearances while removing
  // the wrong identities and most loose poses (docs/RESULTS.md, "Appearance").
  float min_appearance = 0.7f;
  // Not in the paper: a pose with less keypoint support than min_inliers and
  // min_verification_z ask is still kept when its appearance confirms it:
  // at least confirmed_min_inliers distinct inliers (0: never), a
  // verification z of confirmed_min_verification_z and an appearance
  // correlation of confirmed_min_appearance. Small and far signs carry few
  // keypoints but still look like themselves. Format 6.2; 0 in older files.
  int confirmed_min_inliers = 8;
  float confirmed_min_verification_z = 2.f;
  float confirmed_min_appearance = 0.8f;
  // Not in the paper (issue 14, lever 1): a keygraph correspondence of 3 or
  // more vertices is dropped before RANSAC when the triangle of its first
  // three vertices, sampled in the model's appearance and in the frame
  // through the affine frame they define, correlates below this (zero-mean
  // normalised, in [0, 1)); 0 is off. Correspondences that cannot be judged
  // (no appearance, a tiny or flat triangle) are kept. Format 6.4; 0 (off)
  // in older files. At 0.6: Oxford 400 crops 68.5 / 76.8 % -> 75.8 / 85.8 %
  // within 3 / 10 px, but the held-out 50-sign benchmark 64.6 -> 61.2 %
  // within 10 px and 1.27x the frame time, so off by default then
  // (docs/RESULTS.md, "Triangle patch check"); 0.6 by default since the
  // tilted views, whose extra correspondences it cleans (ViewParams).
  float min_triangle_correlation = 0.6f;
  // Not in the paper (issue 14, lever 2): 1 orders each model's keygraph
  // correspondences by how many keypoint pairs they share with others and
  // samples them progressively (PROSAC), with PROSAC's stopping rule on
  // prefixes holding 16 inlier correspondences; 0 draws uniformly. With the
  // local optimisation's iterated least squares, on against off: Oxford
  // 69.0 -> 74.8 % within 3 px (wrong poses 2 -> 1), real planar pairs
  // 3 / 5 / 5 -> 4 / 6 / 7 within 2 / 5 / 10 px, the sign benchmark within
  // two or three signs of uniform draws over 1 280 signs (seeds 1 to 3;
  // docs/RESULTS.md, "Progressive sampling" and "Local optimisation, and
  // progressive sampling by default"). Format 6.4; 0 (uniform draws) in
  // older files, which keep their draws.
  int progressive_sampling = 1;
};

// Not in the paper: simulated views of each model, rendered by the builder
// (src/builder/model_views.h): the model image at every scale down to the
// smallest sign to be found and at out-of-plane tilts, each with its own
// keypoints, arcs and descriptors mapped back to model pixels. The paper's
// own paradigm (exhaustive on the model side, fast on the scene side): the
// frame's work does not grow with the views except through the search.
struct ViewParams {
  // Smallest long edge, in frame pixels, at which a model must still be
  // found: the views' scale pyramid stops there. 0 disables views (one
  // model image; keypoints from KeypointParams::model_scales).
  float min_size = 40.f;
  float scale_step = 0.7071f;  // each view's scale over the previous one's
  // Largest size, relative to the model image, at which a model must still
  // be found: frontal views each 1 / scale_step larger than the last are
  // added up to it (1: none). For models a camera sees larger than their
  // image, such as a whiteboard photographed from farther away than the
  // frames: at 1.42 the real planar pairs go from 7 / 9 / 9 to 8 / 10 / 10
  // of 14 within 2 / 5 / 10 px (WhiteBoard, 1.44x its model in the scene,
  // is found). Signs are seen smaller than a model image of a few hundred
  // pixels, and there 1.42 costs 3 points at 1 sign and more false
  // detections, so 1 by default (docs/RESULTS.md, "Views larger than the
  // model"). At most sqrt(RansacParams::max_scale_change): the pose check
  // refuses the poses of larger views. Format 6.7; older files read 1.
  float max_scale = 1.f;
  // Largest simulated out-of-plane rotation, degrees (0: frontal only),
  // reached in tilt_levels steps equally spaced in t = 1 / cos(angle);
  // longitudes 72 / t degrees apart (ASIFT's sampling). By default 45
  // degrees in one level (t = 1.41 at 3 longitudes: 4 pyramids with the
  // frontal one), with the triangle check (0.6), circuit completion and
  // 10 leaves (8 since near-neighbour arcs, GraphParams): held-out sign
  // benchmark 63.3 / 62.5 / 63.3 % -> 76.2 / 75.8 / 72.9 % within 10 px at
  // 1 / 10 / 50 signs, Oxford 400 crops 74.8 / 83.8 % -> 78.0 / 91.5 %
  // within 3 / 10 px, for about 1.5x the frame;
  // ASIFT's 60 degrees in two levels (angled_params()) finds a little more
  // for 2.2x (docs/RESULTS.md, "Tilted views at 45 degrees by default").
  float max_tilt = 45.f;
  int tilt_levels = 1;
  // Keypoints of different views closer than this many view pixels (mapped
  // back to the model) are one model keypoint.
  float merge_distance = 1.5f;
  // An arc between the same two model keypoints is stored again for
  // another view only when its descriptor differs by more than this
  // (Euclidean) or its scale attributes by more than one grid step.
  float dedupe_distance = 0.05f;
  // Long edge, in pixels, of the grey image of each model the index stores
  // (its appearance, format 6.2: the model image downsampled by area
  // averaging, never upsampled), which the detector aligns onto the frame
  // to refine and check a pose. 0 stores none (and files older than 6.2
  // read as 0).
  int appearance_size = 128;
};

struct Params {
  KeypointParams keypoints;
  GraphParams graph;
  DescriptorParams descriptor;
  RansacParams ransac;
  ViewParams views;
};

}  // namespace kg
