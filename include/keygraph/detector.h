// Per-frame detection of the models of a ModelIndex (paper sections 5-7).
//
//   kg::ModelIndex index;
//   if (kg::Status s = kg::ModelIndex::open("signs.kgi", index); !s) { ... }
//   kg::Detector detector(index, kg::Limits{}.for_frame(1280, 720));  // allocates here, once
//   if (!detector.status()) { ... }
//   kg::DetectionList found;                 // fixed capacity, no heap
//   detector.detect(kg::ImageView{y_plane, 1280, 720, stride}, found);   // never allocates
//
// Memory: the constructor lays out one workspace for `Limits` (frame size,
// keypoints, keygraphs, correspondences, detections) and allocates it in one
// piece, or uses a buffer the caller supplies; nothing is allocated after
// that (set_options() and detect() included). When a frame needs more than
// the limits allow, detection degrades (the stats' truncated_* flags say
// what was cut) instead of overflowing. A frame larger than max_width x
// max_height is an error (kInvalidArgument).
//
// Settings: everything that makes the frame's descriptors comparable with
// the models' (keypoints, sampling, keygraph structure, descriptors) comes
// from the index and cannot change; how hard to search, how poses are
// estimated and accepted, and which models to look for are DetectOptions,
// which default to the index's and can be changed per detector.
//
// Lifetime and threads: the index must outlive the detector. A Detector is
// not thread-safe; use one per thread (they can share one index, which is
// read-only). Results (DetectionList, stats(), last_matches()) stay valid
// until the next detect() on the same detector.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "keygraph/detection.h"
#include "keygraph/image.h"
#include "keygraph/model_index.h"
#include "keygraph/params.h"
#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg {

class FramePipeline;  // the frame's stages (src/core/pipeline)

// Capacities of the per-frame work, from which the workspace is sized.
// Reaching one degrades detection (the stats say what was cut); it never
// overflows. Detector::workspace_bytes() gives the memory they need (about
// 30 MB for the defaults at 640x480, 16 MB of it the arc pool:
// tests/core/test_runtime_memory.cpp).
struct Limits {
  static constexpr int kMaxSide = 16384;  // the largest max_width, max_height
  int max_width = 640;                    // largest frame, pixels
  int max_height = 480;
  int max_keypoints = 4000;        // detector output, strongest kept
  int max_scene_keypoints = 2000;  // after Chebyshev sampling
  int max_arc_matches = 4096;      // model arcs kept per scene arc query
  // Model arcs kept over all queries of a frame (8 bytes each): 2 M holds
  // a 640x480 frame's look-ups in a 50-sign index, whose search budget
  // grows with it (DescriptorParams::search_reference_models); 512 K cut
  // them off. Indexes of hundreds of models may fill it again, and a grown
  // budget may find more than max_arc_matches arcs for one query: both
  // degrade as any limit does (DetectStats::truncated_arc_matches).
  int max_arc_pool = 1 << 21;
  int max_correspondences = 20000;  // keygraph correspondences per frame
  int max_detections = 16;          // at most kMaxDetections
  // Threads a detect() uses, counting the caller's (1..64): threads - 1
  // workers are started with the detector and joined with it, each with its
  // own share of the workspace (mostly the join's buffers). The
  // detections are the same for any count, bit for bit. More than one
  // helps with circuit completion on (the default): the look-ups, joins
  // and arc descriptors run on every thread; the rest runs on the caller.
  int threads = 1;
  // The same limits for frames up to width x height.
  Limits for_frame(int width, int height) const {
    Limits l = *this;
    l.max_width = width;
    l.max_height = height;
    return l;
  }
};

// Settings of the frame's work that an application may change per detector
// without rebuilding the index. DetectOptions::from(index) gives the
// index's own (what `keygraph build` stored), which a Detector starts with;
// set_options() changes them between frames. `keygraph detect`, `live`,
// `bench` and `eval` set them with --set NAME=VALUE
// (detect_option_names()).
struct DetectOptions {
  // Pose estimation and acceptance: RANSAC's confidence, iteration cap and
  // seed, the inlier threshold, the minimum support, the verification and
  // appearance checks, the triangle patch check (keygraph/params.h,
  // RansacParams, has each field's meaning and range).
  RansacParams ransac;
  // Search effort: tree leaves visited per scene arc (0: exact search, the
  // slowest), and the index size (models) up to which that budget holds;
  // it grows with the square root of the models beyond (0: fixed).
  // DescriptorParams has both; more leaves find more of a model's arcs for
  // more time.
  int max_search_leaves = 8;
  int search_reference_models = 10;
  // Model arcs kept per scene arc, per leaf of the budget (so the cap
  // follows the index's size as the leaves do): a query keeps the best
  // ranked search_arcs_per_leaf x leaves of the arcs it finds (~30 a leaf
  // within the similarity threshold), by descriptor distance and scale
  // attributes; 0 (the default) keeps them all. Not stored in the index.
  // 20 cuts a 640x480 frame's instructions by ~10 % (half the
  // correspondences) but loses ~3 points of signs at 1280x720 and recall
  // at 200 models without circuit completion (docs/RESULTS.md, "Fewer
  // model arcs per scene arc"): an opt-in where time counts more.
  static constexpr int kDefaultSearchArcsPerLeaf = 0;
  int search_arcs_per_leaf = kDefaultSearchArcsPerLeaf;
  // RANSAC stops a model's attempt after this many draws when no hypothesis
  // so far has the support an instance needs (ransac.min_inlier_keygraphs
  // and the fewest inliers any acceptance rule takes); 0 draws to the cap
  // (ransac.max_iterations) as the paper does. Most of the cap's draws go
  // to models absent from the frame, whose pools hold no instance. The
  // default 2000 finds what 0 finds on every detection set, with about
  // half the iterations (1000 lost a sign at 1280x720). Not stored in the
  // index (docs/RESULTS.md, "RANSAC on barren pools").
  static constexpr int kDefaultRansacBarrenDraws = 2000;
  int ransac_barren_draws = kDefaultRansacBarrenDraws;
  // Aligning only what can be accepted. A cluster's appearance alignment
  // (for ransac.min_appearance and the confirmed and small rules) stops
  // after the coarse (half-resolution) level when neither the cluster's
  // pose nor the coarse level's fit correlates with the frame at
  // align_coarse_min_ncc or more, and does not start when the pose
  // correlates under align_min_ncc: the cluster is then rejected for its
  // appearance (the fine level is most of an alignment's cost). With
  // align_coarse_min_ncc above -1, a cluster whose pose and an instance of
  // its model already found hold each other's centres (a repeat, rejected
  // either way) is neither refined further nor aligned. [-1, 1] each; -1
  // never (both -1: every cluster judged in full, as before); values above
  // the lowest appearance an acceptance rule takes act as that value. On
  // the tuning sets no accepted cluster's pose correlated under 0.43, nor
  // under 0.52 with its coarse fit. Not stored in the index (docs/RESULTS.md,
  // "Aligning only what can be accepted").
  static constexpr double kDefaultAlignCoarseMinNcc = 0.45;
  double align_coarse_min_ncc = kDefaultAlignCoarseMinNcc;
  static constexpr double kDefaultAlignMinNcc = 0.3;
  double align_min_ncc = kDefaultAlignMinNcc;
  // keypoints.scene_upsample 3 only (the frame, then the frame upsampled
  // 2x), not stored in the index:
  // - upsampled_min_confidence: an instance that only the upsampled pass
  //   found (its outline overlaps no detection of the frame's pass) is
  //   dropped when its confidence is below this; [0, 1], 0 keeps it as the
  //   pose stage accepted it. Default 0.7: on the tuning sets the upsampled
  //   pass's own false detections were near misses of weak support, and
  //   every right one it alone found had a confidence of 0.75 or more.
  // - upsampled_scene_keypoints: the upsampled pass samples at most this
  //   many scene keypoints (the strongest, as Limits::max_scene_keypoints
  //   does), fewer than the frame's pass may: its search and joins cost in
  //   proportion and the small instances it is there for keep their
  //   keypoints. >= 0, 0: Limits::max_scene_keypoints; default 1000.
  // docs/RESULTS.md, "The small-sign opt-in: its false detections and
  // cost (issue 38)".
  static constexpr double kDefaultUpsampledMinConfidence = 0.7;
  double upsampled_min_confidence = kDefaultUpsampledMinConfidence;
  static constexpr int kDefaultUpsampledSceneKeypoints = 1000;
  int upsampled_scene_keypoints = kDefaultUpsampledSceneKeypoints;
  // Detections whose confidence (Detection::confidence, in [0, 1]) is below
  // this are dropped: 0 keeps every detection that passed the checks; 0.5
  // keeps those more likely right than wrong.
  double min_confidence = 0.0;
  // A time budget for one detect(), milliseconds (steady clock, from the
  // call): when it is spent the detector stops at the next check (between
  // stages, every few dozen keygraphs of the selection, between models of
  // the pose), returns what it found so far and sets
  // DetectStats::stopped_early. 0: no budget. What a frame finds within a
  // budget depends on the machine's speed (and, with threads, on timing).
  double time_budget_ms = 0.0;
  // The models to look for: `model_count` ids of ModelIndex::model(), read
  // by set_options() and the constructor (the array is not kept). nullptr
  // (the default) looks for every model. Correspondences with other models
  // are dropped before the pose; the search itself is the index's.
  const std::int32_t* models = nullptr;
  std::size_t model_count = 0;

  // The index's own settings, every model searched.
  static DetectOptions from(const ModelIndex& index);
};

// Sets the option `name` ("ransac.seed", "descriptor.max_search_leaves",
// "min_confidence"; keygraph/param_text.h spells the values) of `options`.
// kInvalidArgument for a name that is not a runtime option (the index's
// other parameters are fixed: rebuild the index to change them) or a value
// that does not parse; ranges are checked by set_options().
Status set_detect_option(DetectOptions& options, std::string_view name, std::string_view value);
// The names set_detect_option() accepts.
std::vector<std::string> detect_option_names();

class Detector {
 public:
  // Allocates the workspace for `limits` (one allocation), with the index's
  // options.
  explicit Detector(const ModelIndex& index, const Limits& limits = Limits{});
  // The same with `options` (as set_options() takes them).
  Detector(const ModelIndex& index, const Limits& limits, const DetectOptions& options);
  // Uses `size` bytes at `buffer` (64-byte aligned, at least
  // workspace_bytes(index, limits)) as the workspace and allocates nothing;
  // the caller keeps the buffer alive and untouched while the detector
  // exists. A buffer too small or misaligned leaves the detector failed:
  // status() says why and detect() returns that status.
  Detector(const ModelIndex& index, const Limits& limits, void* buffer, std::size_t size);
  ~Detector();
  Detector(Detector&&) noexcept;
  Detector& operator=(Detector&&) noexcept;
  Detector(const Detector&) = delete;
  Detector& operator=(const Detector&) = delete;

  // Bytes of workspace a Detector for `index` and `limits` uses. Found by
  // laying the workspace out once, which allocates temporarily: call it
  // where a heap exists (the figure is the same on every run of one build).
  static std::size_t workspace_bytes(const ModelIndex& index, const Limits& limits);
  std::size_t workspace_bytes() const;
  // Bytes of the workspace handed out so far: equal to workspace_bytes()
  // after construction and, since detect() allocates nothing, ever after.
  std::size_t workspace_used() const;
  // Ok, or why construction failed (limits or options out of range, buffer
  // too small).
  const Status& status() const;
  const Limits& limits() const;

  // Changes the options for the next frames (allocates nothing). Checked
  // first: kInvalidArgument for a value out of range or a model id not in
  // the index, and the options in effect stay as they were.
  Status set_options(const DetectOptions& options);
  // The check set_options() and the constructor make: every value in range
  // and every model id in `index`.
  static Status check_options(const ModelIndex& index, const DetectOptions& options);
  // The options in effect; their `models` is nullptr (searches_model()
  // says which models are searched).
  const DetectOptions& options() const;
  // Whether model `id` is searched (set_options()).
  bool searches_model(int id) const;

  // Detects with the built-in keypoint detector (the index's detector must
  // be kHessian, and the index must have no vertex descriptors). Clears and
  // fills `out`.
  Status detect(ImageView frame, DetectionList& out);
  // Detects with keypoints computed by the caller (e.g. MSER on a desktop):
  // the same pipeline from the sampling step on. The index must have no
  // vertex descriptors.
  Status detect(ImageView frame, const Keypoint* keypoints, int count, DetectionList& out);
  // The same with the keypoints' vertex descriptors (the core cannot compute
  // SIFT): kVertexDescriptorSize bytes per keypoint, row i describing
  // keypoints[i], computed as the index's were (DesktopDetector does).
  // Required when the index has vertex descriptors (params().descriptor.
  // vertex_descriptor != kNone), ignored otherwise; nullptr means none.
  Status detect(ImageView frame, const Keypoint* keypoints, int count,
                const std::uint8_t* vertex_descriptors, DetectionList& out);

  const DetectStats& stats() const;
  // Keygraph correspondences selected in the last frame (evaluation, tests).
  ConstSpan<KeygraphMatch> last_matches() const;
  // Scene keypoints (after sampling) of the last frame.
  ConstSpan<Keypoint> last_keypoints() const;
  const ModelIndex& index() const;

 private:
  struct Header;  // at the start of the workspace: its allocator and the pipeline
  static std::size_t header_bytes();
  void place(void* buffer, std::size_t size, const DetectOptions& options);
  void release();

  const ModelIndex* index_ = nullptr;
  Header* header_ = nullptr;           // at the start of the workspace
  FramePipeline* pipeline_ = nullptr;  // header_->pipeline
  void* owned_ = nullptr;              // the workspace, when the detector allocated it
  std::size_t workspace_size_ = 0;
  Limits limits_;
  Status status_;
};

}  // namespace kg
