/* keygraph's C API: the detector of keygraph/detector.h behind a C ABI, for
 * C programs and for the bindings (Java/JNI, Python through ctypes, Swift).
 * C99; no C++ types. Link libkeygraph_capi.a and libkeygraph_core.a
 * (pkg-config keygraph-c, CMake keygraph::capi) with a C++ driver or with
 * -lstdc++ -lm after them: the implementation is C++.
 *
 *   kg_index* index = NULL;
 *   if (kg_index_open("signs.kgi", &index) != KG_OK) { puts(kg_last_error()); ... }
 *   kg_limits limits;
 *   kg_limits_default(&limits);
 *   limits.max_width = 1280;                 (the largest frame)
 *   limits.max_height = 720;
 *   kg_detector* det = NULL;
 *   if (kg_detector_create(index, &limits, &det) != KG_OK) { ... }   (allocates here, once)
 *   kg_detector_set_option(det, "ransac.seed", "7");                (optional, by name)
 *   kg_image frame = {y_plane, 1280, 720, stride};
 *   kg_detection found[KG_MAX_DETECTIONS];
 *   size_t count = 0;
 *   if (kg_detect(det, &frame, found, KG_MAX_DETECTIONS, &count) == KG_OK)   (never allocates)
 *     for (size_t i = 0; i < count; ++i) printf("%s\n", found[i].model_name);
 *   kg_detector_destroy(det);
 *   kg_index_destroy(index);
 *
 * Conventions (those of the C++ API): pixel (x, y) is column x, row y, the
 * centre of the top-left pixel is (0, 0), y grows downwards; a homography
 * is row-major and maps model pixels (of the model image the index was
 * built from, or its ROI) to frame pixels: [x_f, y_f, w]^T = H [x_m, y_m, 1]^T.
 *
 * Errors: every function that can fail returns a kg_status (KG_OK is 0).
 * The numbers are kg::StatusCode's (keygraph/status.h) and stable: new codes
 * are only ever appended. kg_status_name() names a code; kg_last_error()
 * gives the one-line message of the last call that failed on the calling
 * thread. A null handle or pointer, a bad stride or a frame larger than
 * the limits is KG_INVALID_ARGUMENT, never a crash.
 *
 * Ownership and lifetime:
 *  - Handles (kg_index, kg_detector, kg_tracker) are made by the *_open,
 *    *_read, *_from_memory and *_create functions and released by the
 *    matching *_destroy, which accepts NULL. A handle is never used after
 *    its *_destroy (the C API cannot detect a dangling handle; the Java and
 *    Python bindings refuse closed ones).
 *  - An index must outlive every detector made from it, a detector every
 *    tracker made from it; memory given to kg_index_from_memory() must
 *    outlive the index, unchanged.
 *  - Model names (kg_index_model_name(), kg_detection::model_name) are
 *    NUL-terminated strings owned by the index, valid while it lives.
 *  - Results are copied into arrays the caller owns.
 *
 * Threads: an index is read-only once open and may be shared by any number
 * of detectors on any threads. A detector (with its tracker) is not
 * thread-safe: use one per thread (or lock around it); kg_limits::threads
 * lets one detector use several threads for a frame. kg_last_error() is
 * per thread.
 *
 * Memory: opening an index allocates its handle and a name table (and,
 * for kg_index_read(), a copy of the file); creating a detector allocates
 * its handle and its workspace, sized once from kg_limits, unless the
 * caller supplies the workspace (kg_detector_create_in). kg_detect(),
 * kg_tracker_process() and kg_detector_set_option() allocate nothing when
 * they succeed (tests/capi/test_capi_memory.cpp counts).
 */
#ifndef KEYGRAPH_KEYGRAPH_H
#define KEYGRAPH_KEYGRAPH_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------ status */

/* kg::StatusCode's numbers (keygraph/status.h). */
typedef enum kg_status {
  KG_OK = 0,
  KG_INVALID_ARGUMENT = 1,    /* a bad parameter, option, frame, handle or limit */
  KG_NOT_FOUND = 2,           /* a missing file or model */
  KG_IO_ERROR = 3,            /* reading failed */
  KG_CORRUPT_DATA = 4,        /* a malformed index */
  KG_UNSUPPORTED_VERSION = 5, /* an index of a format version this build cannot read */
  KG_RESOURCE_EXHAUSTED = 6,  /* a size beyond a limit, or out of memory */
  KG_TIMEOUT = 7,             /* (frame sources) */
  KG_END_OF_STREAM = 8,       /* (frame sources) */
  KG_BAD_FRAME = 9            /* (frame sources) */
} kg_status;

/* The code's name without the prefix ("InvalidArgument"), static text;
 * "Unknown" for a number that is no code. */
const char* kg_status_name(kg_status status);

/* The message of the last call that failed on this thread ("index
 * signs.kgi: bad checksum in section 3"), one line, at most 511 bytes;
 * "" when none has failed. Valid until the next failing call on this
 * thread. Successful calls leave it as it was. */
const char* kg_last_error(void);

/* ------------------------------------------------------------ version */

/* The library version, "MAJOR.MINOR.PATCH" (the project's VERSION file),
 * static text. */
const char* kg_version(void);

/* ------------------------------------------------------------ index */

/* A model index (.kgi), opened and validated: every count, offset and
 * checksum is checked before use, so a corrupt or hostile file is an error
 * (KG_CORRUPT_DATA, KG_UNSUPPORTED_VERSION), never a crash. */
typedef struct kg_index kg_index;

/* Maps the file at `path` read-only (ModelIndex::open). Safe while the file
 * is only ever replaced by rename, as `keygraph build` writes it; a file
 * changed in place while mapped shows bytes that were never validated:
 * use kg_index_read() then. */
kg_status kg_index_open(const char* path, kg_index** out);
/* Reads the file at `path` into memory the index owns (ModelIndex::read):
 * later changes to the file never reach it. */
kg_status kg_index_read(const char* path, kg_index** out);
/* Uses `size` bytes at `data`, which the caller owns (a buffer read or
 * mapped by the caller, or linked into firmware) and keeps alive and
 * unchanged until kg_index_destroy(). Alignment rule: `data` must be
 * 64-byte aligned (the sections are aligned for in-place use);
 * KG_INVALID_ARGUMENT otherwise. Nothing is copied. */
kg_status kg_index_from_memory(const void* data, size_t size, kg_index** out);
/* Releases the index (and its mapping or copy); NULL is ignored. Every
 * detector made from it must be destroyed first. */
void kg_index_destroy(kg_index* index);

/* The index's format version (6 and 10 for a format 6.10 file); KG_INVALID_ARGUMENT
 * for a NULL argument. */
kg_status kg_index_version(const kg_index* index, int* major, int* minor);
/* The number of models; 0 for NULL. */
int kg_index_model_count(const kg_index* index);
/* Model `model`'s name, NUL-terminated, owned by the index; NULL for a
 * NULL index or a model not in [0, kg_index_model_count()). */
const char* kg_index_model_name(const kg_index* index, int model);

typedef struct kg_model_info {
  const char* name; /* as kg_index_model_name() */
  double width;     /* the model image's size, pixels */
  double height;
  double outline[4][2]; /* corners (x, y), clockwise from the top-left, model pixels */
  uint32_t keypoints;   /* model keypoints (of every view) */
} kg_model_info;
kg_status kg_index_model_info(const kg_index* index, int model, kg_model_info* out);

/* ------------------------------------------------------------ detector */

/* Capacities of the per-frame work (kg::Limits), from which the
 * detector's workspace is sized once. Reaching one degrades detection (the
 * stats' truncated_* flags say what was cut); it never overflows. */
typedef struct kg_limits {
  int max_width;           /* largest frame, pixels (1..16384; default 640) */
  int max_height;          /* (1..16384; default 480) */
  int max_keypoints;       /* detector output, strongest kept (default 4000) */
  int max_scene_keypoints; /* after sampling (default 2000) */
  int max_arc_matches;     /* model arcs kept per scene arc query (default 4096) */
  int max_arc_pool;        /* model arcs kept over a frame's queries (default 2^21) */
  int max_correspondences; /* keygraph correspondences per frame (default 20000) */
  int max_detections;      /* 1..KG_MAX_DETECTIONS (default 16) */
  int threads;             /* threads a detect uses, counting the caller's (1..64;
                              default 1); the detections are the same for any count */
} kg_limits;

/* The most detections a frame can return (kg::kMaxDetections). */
#define KG_MAX_DETECTIONS 64

/* Fills `out` with kg::Limits{}'s defaults. */
void kg_limits_default(kg_limits* out);

typedef struct kg_detector kg_detector;

/* Creates a detector for `index` with `limits` (NULL: the defaults) and the
 * index's own options, allocating its workspace (one allocation; about 30
 * MB for the defaults). KG_INVALID_ARGUMENT for limits out of range. */
kg_status kg_detector_create(const kg_index* index, const kg_limits* limits, kg_detector** out);
/* The workspace a detector for `index` and `limits` (NULL: the defaults)
 * needs, bytes; 0 for limits out of range or a NULL index. Lays the
 * workspace out once, which allocates temporarily. */
size_t kg_detector_workspace_bytes(const kg_index* index, const kg_limits* limits);
/* The same in a workspace the caller supplies: `size` bytes at `buffer`,
 * 64-byte aligned, at least kg_detector_workspace_bytes(); the caller keeps
 * it alive and untouched until kg_detector_destroy(). Only the handle is
 * allocated. KG_RESOURCE_EXHAUSTED for a buffer too small, KG_INVALID_ARGUMENT
 * for one misaligned. */
kg_status kg_detector_create_in(const kg_index* index, const kg_limits* limits, void* buffer,
                                size_t size, kg_detector** out);
/* Stops the detector's threads and releases it (not a caller's
 * workspace); NULL is ignored. */
void kg_detector_destroy(kg_detector* detector);

/* Sets the runtime option `name` to `value` for the next frames, as
 * `keygraph detect --set NAME=VALUE` does: "ransac.seed", "ransac.*",
 * "descriptor.max_search_leaves", "descriptor.search_reference_models",
 * "min_confidence" (0..1), "time_budget_ms" (0: none). Checked; on error
 * (KG_INVALID_ARGUMENT: an unknown name, a parameter fixed by the index, a
 * value that does not parse or is out of range) the options stay as they
 * were. Allocates nothing when it succeeds. */
kg_status kg_detector_set_option(kg_detector* detector, const char* name, const char* value);
/* The models to look for: `count` ids of the index (NULL or 0: every
 * model). KG_INVALID_ARGUMENT for an id not in the index. */
kg_status kg_detector_set_models(kg_detector* detector, const int32_t* ids, size_t count);

/* An 8-bit grey image the caller owns: `width` x `height` pixels, row y at
 * data + y * stride (stride >= width); the (height - 1) * stride + width
 * bytes from `data` must be readable (the C API cannot check that; the
 * Java and Python bindings do). The Y plane of an NV12, NV21 or
 * YUV420 camera frame is one as it is. */
typedef struct kg_image {
  const uint8_t* data;
  int width;
  int height;
  ptrdiff_t stride; /* bytes from one row to the next */
} kg_image;

typedef struct kg_detection {
  int model_id;           /* index of the model in the index */
  const char* model_name; /* NUL-terminated, owned by the index */
  double homography[9];   /* row-major, model pixels -> frame pixels */
  double corners[4][2];   /* the model's outline (kg_model_info) in the frame */
  int inliers;            /* distinct keypoint correspondences within the threshold */
  int inlier_keygraphs;   /* keygraph correspondences with every vertex an inlier */
  double score;           /* fraction of the model's keypoints confirmed in the frame */
  double chance;          /* the same for the pose shifted by 3 thresholds */
  double rms_error;       /* reprojection error of the inliers, pixels */
  double verification_z;  /* binomial z-score of score against chance */
  double appearance;      /* appearance correlation in [0, 1]; -1 when not measured */
  double confidence;      /* estimated probability, in [0, 1], that it is right */
  int ransac_iterations;
  int track_id; /* kg_tracker_process() only: the object's id while followed; -1 otherwise */
  int tracked;  /* kg_tracker_process() only: 1 when confirmed around its prediction */
} kg_detection;

/* Detects the index's models in `image` (the index's keypoint detector
 * must be the built-in Hessian one: `keygraph build`'s default). Writes at
 * most `capacity` detections to `out` and their number to `count`
 * (detections beyond `capacity` are dropped, and the stats say so).
 * KG_INVALID_ARGUMENT for a NULL argument, an empty image, a stride below
 * the width, or an image larger than the limits. Allocates nothing. The
 * strings in `out` live with the index; the rest is the caller's. */
kg_status kg_detect(kg_detector* detector, const kg_image* image, kg_detection* out,
                    size_t capacity, size_t* count);

/* The last frame's statistics (kg::DetectStats). */
typedef struct kg_stats {
  int keypoints;           /* detected in the frame */
  int sampled_keypoints;   /* after sampling */
  int keygraphs;           /* scene keygraphs */
  int arcs_described;      /* scene arcs with a descriptor */
  long long arc_matches;   /* similar model arcs found, summed */
  int correspondences;     /* keygraph correspondences selected */
  int ransac_iterations;   /* summed over models and instances */
  int truncated_keypoints; /* 1: a limit cut this stage's output */
  int truncated_arc_matches;
  int truncated_correspondences;
  int truncated_detections; /* max_detections or the caller's capacity */
  double ms_keypoints;      /* time per stage, milliseconds */
  double ms_graph;
  double ms_describe;
  double ms_select;
  double ms_pose;
  const char* stopped_early; /* the stage a time budget ran out in, static text; NULL if none */
} kg_stats;
kg_status kg_detector_stats(const kg_detector* detector, kg_stats* out);

/* ------------------------------------------------------------ tracker */

/* Follows what a detector finds from frame to frame (kg::Tracker,
 * keygraph/tracker.h): each object's corners are predicted and confirmed by
 * aligning the model's stored appearance, full detection runs when nothing
 * is followed, when an object is lost and every detect_interval frames, and
 * an object keeps its track_id while it is followed. The detector must
 * outlive the tracker, keep its limits and serve no other caller while the
 * tracker uses it. Not thread-safe; frames in order. */
typedef struct kg_tracker kg_tracker;

typedef struct kg_tracker_options {
  int detect_interval;    /* full detection every this many frames (>= 1; default 10) */
  double min_correlation; /* a track is kept while its appearance correlates this
                             much, in (0, 1) (default 0.75) */
  int max_tracks;         /* objects followed at once, 1..KG_MAX_DETECTIONS (default 16) */
  double smoothing;       /* corner smoothing in [0, 1) (default 0: none) */
} kg_tracker_options;

/* Fills `out` with kg::TrackerOptions{}'s defaults. */
void kg_tracker_options_default(kg_tracker_options* out);
/* Creates a tracker over `detector` with `options` (NULL: the defaults),
 * reserving what it uses per frame (one allocation besides the handle).
 * KG_INVALID_ARGUMENT for options out of range or a failed detector. An
 * index without model appearances (format < 6.2) cannot be tracked: the
 * tracker is made, detects every frame, and kg_tracker_can_track() is 0. */
kg_status kg_tracker_create(kg_detector* detector, const kg_tracker_options* options,
                            kg_tracker** out);
void kg_tracker_destroy(kg_tracker* tracker);
/* 1 when the index lets the tracker follow objects, 0 otherwise (and for NULL). */
int kg_tracker_can_track(const kg_tracker* tracker);
/* The objects in `image`, as kg_detect() returns them plus track_id and
 * tracked; a frame larger than the detector's limits is KG_INVALID_ARGUMENT.
 * Allocates nothing. */
kg_status kg_tracker_process(kg_tracker* tracker, const kg_image* image, kg_detection* out,
                             size_t capacity, size_t* count);
/* Forgets every track (a new scene, a camera switch). */
void kg_tracker_reset(kg_tracker* tracker);

typedef struct kg_tracking_stats {
  int tracks;       /* objects followed after the last frame */
  int confirmed;    /* tracks confirmed around their prediction */
  int lost;         /* tracks dropped on the last frame */
  int detected;     /* 1: full detection ran on the last frame */
  double ms_track;  /* the alignments, milliseconds */
  double ms_detect; /* the detection, when it ran */
  long long frames; /* frames since creation or kg_tracker_reset() */
  long long detected_frames;
} kg_tracking_stats;
kg_status kg_tracker_stats(const kg_tracker* tracker, kg_tracking_stats* out);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* KEYGRAPH_KEYGRAPH_H */
