// The core's view of a ModelIndex's search tree: the tree points and leaf
// bounds in the index's descriptor encoding, the internal nodes, and a
// prefetch of an arc's record. Internal: the public ModelIndex hides them
// (include/keygraph/model_index.h befriends this struct).
#pragma once

#include <cstdint>

#include "core/description/arc_types.h"
#include "core/index/kdtree.h"
#include "keygraph/model_index.h"

namespace kg {

struct IndexInternals {
  // Per tree slot a point of kSearchDims components (the arc descriptor,
  // then its scale attributes, core/description/arc_attributes.h), from the
  // accessor of the index's encoding (the others return nullptr).
  static const ArcSearchPoint* tree_points_f32(const ModelIndex& index);
  static const ArcSearchPointI16* tree_points_i16(const ModelIndex& index);
  static const ArcSearchPointI8* tree_points_i8(const ModelIndex& index);
  // Per tree leaf (2^tree_depth(), left to right) the component-wise
  // minimum and maximum of its points, in the same encoding.
  static const ArcSearchPoint* leaf_bounds_f32(const ModelIndex& index);
  static const ArcSearchPointI16* leaf_bounds_i16(const ModelIndex& index);
  static const ArcSearchPointI8* leaf_bounds_i8(const ModelIndex& index);
  // The internal nodes: KdNode for float32, KdNodeInt for int16 and int8.
  static const KdNode* tree_nodes_f32(const ModelIndex& index);
  static const KdNodeInt* tree_nodes_int(const ModelIndex& index);

  // The arcs by tree slot, as ModelIndex::arc() reads them.
  static KdArcKeys arc_keys(const ModelIndex& index) {
    return {index.arc_from_, index.arc_to_offset_};
  }
  // Asks the cache for arc(slot)'s memory: a hint, no effect on results. A
  // look-up converts its slots after requesting them all, so the misses of
  // these random reads overlap.
  static void prefetch_arc(const ModelIndex& index, std::uint32_t slot) {
#if defined(__GNUC__)
    __builtin_prefetch(index.arc_from_ + slot);
    __builtin_prefetch(index.arc_to_offset_ + slot);
#else
    (void)index;
    (void)slot;
#endif
  }
};

}  // namespace kg
