// The model index (.kgi): every model's keypoints, arcs, arc descriptors and
// the search tree over them, optionally vertex (SIFT) descriptors, plus the
// pipeline parameters they were built with. Layout: docs/FORMAT.md.
//
// Loading is validation, not construction: open() reads the file into one
// aligned buffer and view() checks every count, offset, size, checksum and
// stored index before anything is used; the accessors then point into that
// memory. A corrupt or hostile file yields an error Status, never a crash.
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

struct KdNode;

struct ModelInfo {
  std::string_view name;
  float width = 0.f;  // model image size in pixels
  float height = 0.f;
  Point2f outline[4];                // model outline (corners, clockwise on screen) in model pixels
  std::uint32_t keypoint_begin = 0;  // global keypoint ids [begin, begin + count)
  std::uint32_t keypoint_count = 0;
  std::uint32_t arc_begin = 0;  // global arc ids [begin, begin + count)
  std::uint32_t arc_count = 0;
  std::uint64_t keygraph_count = 0;  // model keygraphs (for reports)
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

  // Reads and validates the file at `path`.
  static Status open(const std::string& path, ModelIndex& out);
  // Validates and uses `size` bytes at `data`, which the caller owns and must
  // keep alive and unchanged while `out` (or a Detector using it) exists.
  // `data` must be 64-byte aligned.
  static Status view(const std::uint8_t* data, std::size_t size, ModelIndex& out);

  bool empty() const { return model_count_ == 0; }
  const Params& params() const { return params_; }
  std::uint16_t version_major() const { return version_major_; }
  std::uint16_t version_minor() const { return version_minor_; }

  int model_count() const { return static_cast<int>(model_count_); }
  ModelInfo model(int i) const;
  // Model owning a global arc id (binary search over the models' arc ranges).
  int model_of_arc(std::uint32_t arc) const;
  // Model owning a global keypoint id.
  int model_of_keypoint(std::uint32_t keypoint) const;

  std::uint32_t keypoint_count() const { return keypoint_count_; }
  const Point2f* keypoints() const { return keypoints_; }
  std::uint32_t arc_count() const { return arc_count_; }
  const ModelArc* arcs() const { return arcs_; }

  // Vertex descriptors (Params::descriptor.vertex_descriptor), one per
  // keypoint, kVertexDescriptorSize bytes each in keypoint order; nullptr
  // when the index has none (vertex_descriptor == kNone).
  const std::uint8_t* vertex_descriptors() const { return vertex_descriptors_; }

  // Search tree over arc descriptors (see core/kdtree.h for the layout).
  const ArcDescriptor* tree_points() const { return tree_points_; }
  const std::uint32_t* tree_ids() const { return tree_ids_; }
  const KdNode* tree_nodes() const { return tree_nodes_; }
  int tree_depth() const { return tree_depth_; }

  std::size_t byte_size() const { return size_; }

 private:
  Status validate(const std::uint8_t* data, std::size_t size);
  int last_model_starting_at_or_before(std::size_t field, std::uint32_t id) const;

  struct AlignedFree {
    void operator()(std::uint8_t* p) const;
  };
  std::unique_ptr<std::uint8_t, AlignedFree> owned_;
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
  const ModelArc* arcs_ = nullptr;
  std::uint32_t arc_count_ = 0;
  const ArcDescriptor* tree_points_ = nullptr;
  const std::uint32_t* tree_ids_ = nullptr;
  const KdNode* tree_nodes_ = nullptr;
  int tree_depth_ = 0;
  const std::uint8_t* vertex_descriptors_ = nullptr;
};

}  // namespace kg
