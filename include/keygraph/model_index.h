// The model index (.kgi): every model's keypoints, arcs, arc descriptors and
// the search tree over them, optionally vertex (SIFT) descriptors, plus the
// pipeline parameters they were built with. Layout: docs/FORMAT.md.
//
// Loading is validation, not construction: open() maps the file read-only
// (or, where mapping fails, reads it into one aligned buffer) and view()
// uses caller-owned memory; both check every count, offset, size, checksum
// and stored index before anything is used, and the accessors then point
// into that memory. A corrupt or hostile file yields an error Status, never
// a crash. Neither allocates memory proportional to the file (open()'s
// fallback buffer aside).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "keygraph/params.h"
#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg {

struct IndexInternals;  // the core's access to the search tree (src/core/index)

struct ModelInfo {
  std::string_view name;
  float width = 0.f;  // model image size in pixels
  float height = 0.f;
  Point2f outline[4];                // model outline (corners, clockwise on screen) in model pixels
  std::uint32_t keypoint_begin = 0;  // global keypoint ids [begin, begin + count)
  std::uint32_t keypoint_count = 0;
  // Arcs between this model's keypoints (informational: arcs are stored in
  // search-tree order, all models mixed; an arc's model is its keypoints').
  std::uint32_t arc_count = 0;
  std::uint64_t keygraph_count = 0;  // model keygraphs (for reports)
};

// The quality report `keygraph build` stores with the models (format 6.1,
// docs/FORMAT.md sections 12-14; measured by builder/model_quality.h, rated
// and printed by `keygraph inspect`). Informational: detection never reads it.
struct ViewQuality {
  float scale = 1.f;            // uniform scale of the simulated view (builder/model_views.h)
  float tilt = 1.f;             // 1 / cos(tilt angle)
  float longitude = 0.f;        // direction of the tilt, degrees
  std::uint32_t keypoints = 0;  // keypoints the view's image showed inside the model
  std::uint32_t arcs = 0;       // arcs described in the view (before deduplication)
  std::uint32_t keygraphs = 0;  // keygraphs over those arcs (saturated)
};
struct ModelQuality {
  std::uint32_t view_begin = 0;  // its views: view_quality(view_begin ..)
  std::uint32_t view_count = 0;
  // Arcs with a near-identical arc (descriptor and scale attributes) in
  // another model of the index.
  std::uint32_t shared_arcs = 0;
  // Long edge in frame pixels of the smallest view that still carries
  // enough keypoints and keygraphs to be found; 0 when no view does.
  float smallest_size = 0.f;
  // Long edge of the scene the model was rendered into to look for
  // look-alikes; 0 when that check was not run.
  float scene_size = 0.f;
  bool found_in_scene = false;  // the detector found the model in that scene
};
// The model `shown` was rendered as a scene and the detector, with the
// whole index, found model `detected` in it.
struct LookAlike {
  std::uint32_t shown = 0;
  std::uint32_t detected = 0;
};

// A model's appearance (format 6.2, docs/FORMAT.md sections 15-16): the
// model image (its ROI) resampled by area averaging so that its long edge
// is Params::views.appearance_size pixels (never upsampled: a model smaller
// than that is stored at its own size), 8-bit grey, row-major,
// width * height bytes without padding. Appearance pixel (u, v) covers
// model pixels [u / scale, (u + 1) / scale) x [v / scale, (v + 1) / scale),
// so its centre is model point ((u + 0.5) / scale - 0.5,
// (v + 0.5) / scale - 0.5).
struct ModelAppearance {
  const std::uint8_t* pixels = nullptr;  // nullptr: none stored
  int width = 0;
  int height = 0;
  // Appearance pixels per model pixel, the same along both axes: the long
  // edge's ratio (width / model width for a model at least as wide as
  // high); 1 for a model stored at its own size.
  float scale = 0.f;
  bool empty() const { return pixels == nullptr; }
};

// A directed model arc between two keypoints of the same model (global ids).
struct ModelArc {
  std::uint32_t from = 0;
  std::uint32_t to = 0;
};

class ModelIndex {
 public:
  ModelIndex();
  ~ModelIndex();
  ModelIndex(ModelIndex&&) noexcept;
  ModelIndex& operator=(ModelIndex&&) noexcept;
  ModelIndex(const ModelIndex&) = delete;
  ModelIndex& operator=(const ModelIndex&) = delete;

  // Index files and running processes (the contract):
  //  - Replacing a file by rename (write_index(), keygraph build: a new file
  //    renamed over the old one) is safe for both open() and read(): a
  //    process keeps the old, complete file it loaded.
  //  - Changing a file in place (cp or scp over it, truncate, an editor
  //    writing into it) is NOT safe for open(): the mapping then shows bytes
  //    that were never validated, and reading a page past a shortened end
  //    kills the process with SIGBUS. read() copies the file into memory
  //    once, so later changes never reach the loaded index; use it whenever
  //    the file's immutability is not guaranteed. The keygraph commands all
  //    use read(), and `keygraph live` reloads the index between frames when
  //    the path names a changed file (device, inode, size or mtime).
  // Both open only regular files and never block (a FIFO is refused, not
  // waited on).
  //
  // Maps (POSIX mmap, read-only) and validates the file at `path`; when the
  // file cannot be mapped it is read into an aligned buffer instead. The
  // mapping lives as long as the index; see above for changes to the file.
  static Status open(const std::string& path, ModelIndex& out);
  // Reads the file at `path` into an aligned buffer the index owns (one
  // allocation of the file's size), then validates it: for files that may
  // change while the index is in use.
  static Status read(const std::string& path, ModelIndex& out);
  // Validates and uses `size` bytes at `data`, which the caller owns and must
  // keep alive and unchanged while `out` (or a Detector using it) exists.
  // `data` must be 64-byte aligned.
  static Status view(const std::uint8_t* data, std::size_t size, ModelIndex& out);

  bool empty() const { return model_count_ == 0; }
  // Whether the index is a read-only mapping of its file (open()).
  bool is_mapped() const {
    return owned_ != nullptr && owned_.get_deleter().kind == Release::Kind::kFileMapping;
  }
  const Params& params() const { return params_; }
  std::uint16_t version_major() const { return version_major_; }
  std::uint16_t version_minor() const { return version_minor_; }

  int model_count() const { return static_cast<int>(model_count_); }
  ModelInfo model(int i) const;
  // Model owning a global keypoint id (binary search over the models'
  // keypoint ranges); also the model of an arc (arcs()[i].from).
  int model_of_keypoint(std::uint32_t keypoint) const;

  std::uint32_t keypoint_count() const { return keypoint_count_; }
  const Point2f* keypoints() const { return keypoints_; }
  // Detector scale (sigma in model pixels, 0 when unknown) per keypoint.
  const float* keypoint_scales() const { return keypoint_scales_; }
  // Per keypoint two view scale codes (docs/FORMAT.md, section 11): the
  // finest and the coarsest view of the model that detected it.
  const std::uint8_t* keypoint_views() const { return keypoint_views_; }
  // Arcs in search-tree order: arc(slot) is the arc whose descriptor is in
  // tree slot `slot` (< arc_count()), so a tree query's slots name arcs
  // directly.
  std::uint32_t arc_count() const { return arc_count_; }
  ModelArc arc(std::uint32_t slot) const {
    const std::uint32_t from = arc_from_[slot];
    return {from,
            static_cast<std::uint32_t>(static_cast<std::int64_t>(from) + arc_to_offset_[slot])};
  }

  // Vertex descriptors (Params::descriptor.vertex_descriptor), one per
  // keypoint, kVertexDescriptorSize bytes each in keypoint order; nullptr
  // when the index has none (vertex_descriptor == kNone).
  const std::uint8_t* vertex_descriptors() const { return vertex_descriptors_; }

  // The arc descriptors' encoding (Params::descriptor.encoding).
  DescriptorEncoding descriptor_encoding() const { return params_.descriptor.encoding; }
  // Size of the search tree over the arcs (informational: `keygraph
  // inspect`): its internal nodes and its depth (2^depth leaves).
  std::uint32_t tree_node_count() const { return tree_node_count_; }
  int tree_depth() const { return tree_depth_; }

  // The quality report (see ModelQuality); false for files of format 6.0
  // and indexes written without one.
  bool has_quality() const { return model_quality_ != nullptr; }
  // Model i's record (has_quality() and 0 <= i < model_count(); else empty).
  ModelQuality model_quality(int i) const;
  std::uint32_t view_quality_count() const { return view_quality_count_; }
  ViewQuality view_quality(std::uint32_t i) const;  // i < view_quality_count()
  std::uint32_t look_alike_count() const { return look_alike_count_; }
  LookAlike look_alike(std::uint32_t i) const;  // i < look_alike_count()

  // The models' appearances (see ModelAppearance); false for files older
  // than format 6.2 and indexes built with views.appearance_size 0.
  bool has_appearance() const { return appearances_ != nullptr; }
  // Model `model`'s appearance; empty when none is stored or model is not
  // in [0, model_count()).
  ModelAppearance appearance(int model) const;
  // The largest width * height over the models' appearances (0 when none):
  // what a workspace for aligning any of them needs.
  int max_appearance_pixels() const { return max_appearance_pixels_; }

  // The whole index: size in bytes and its first byte (mapped, owned or the
  // caller's buffer).
  const std::uint8_t* data() const { return data_; }
  std::size_t byte_size() const { return size_; }

 private:
  friend struct IndexInternals;
  Status validate(const std::uint8_t* data, std::size_t size);
  Status validate_quality(const std::uint8_t* quality, std::uint32_t quality_count,
                          const std::uint8_t* views, std::uint32_t view_count,
                          const std::uint8_t* pairs, std::uint32_t pair_count) const;
  Status validate_appearances(const std::uint8_t* records, std::uint32_t record_count,
                              std::uint64_t pixel_count, int& max_pixels) const;

  // Releases open()'s and read()'s memory: unmaps a mapping of the index
  // file, gives read()'s copy back (`pages`: core/support/page_memory.h), or
  // frees an aligned heap buffer; `bytes` is the block's size.
  struct Release {
    enum class Kind : std::uint8_t { kHeap, kFileMapping, kPages };
    Release() noexcept : bytes(0), kind(Kind::kHeap) {}
    Release(std::size_t size, Kind k) noexcept : bytes(size), kind(k) {}
    std::size_t bytes;
    Kind kind;
    void operator()(std::uint8_t* p) const;
  };
  // Validates `memory` (open(), read()) and moves it into `out`.
  static Status adopt(std::unique_ptr<std::uint8_t, Release> memory, std::size_t size,
                      const std::string& path, ModelIndex& out);
  std::unique_ptr<std::uint8_t, Release> owned_;
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
  std::uint16_t version_major_ = 0;
  std::uint16_t version_minor_ = 0;
  Params params_;
  const std::uint8_t* models_ = nullptr;
  std::uint32_t model_count_ = 0;
  const char* strings_ = nullptr;
  std::uint32_t strings_size_ = 0;
  const Point2f* keypoints_ = nullptr;
  std::uint32_t keypoint_count_ = 0;
  const std::uint32_t* arc_from_ = nullptr;
  const std::int16_t* arc_to_offset_ = nullptr;
  std::uint32_t arc_count_ = 0;
  const std::uint8_t* tree_descriptors_ = nullptr;
  const std::uint8_t* tree_nodes_ = nullptr;
  const std::uint8_t* leaf_bounds_ = nullptr;
  std::uint32_t tree_node_count_ = 0;
  int tree_depth_ = 0;
  const std::uint8_t* vertex_descriptors_ = nullptr;
  const float* keypoint_scales_ = nullptr;
  const std::uint8_t* keypoint_views_ = nullptr;
  const std::uint8_t* model_quality_ = nullptr;
  const std::uint8_t* view_quality_ = nullptr;
  std::uint32_t view_quality_count_ = 0;
  const std::uint8_t* look_alikes_ = nullptr;
  std::uint32_t look_alike_count_ = 0;
  const std::uint8_t* appearances_ = nullptr;
  const std::uint8_t* appearance_pixels_ = nullptr;
  int max_appearance_pixels_ = 0;
};

}  // namespace kg
