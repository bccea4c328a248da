// The search of the model index (paper section 8's similar arcs): the
// model arcs whose descriptor is within the similarity threshold of a scene
// arc's, and whose scale attributes agree, found in the index's stored
// tree, exactly or within a budget of leaves (DescriptorParams::
// max_search_leaves).
#pragma once

#include <array>
#include <cstdint>

#include "core/description/arc_types.h"
#include "core/index/kdtree.h"
#include "keygraph/model_index.h"
#include "keygraph/params.h"

namespace kg {

// The model index's search tree in its descriptor encoding, searched with
// float descriptors: the query is quantised as the model descriptors were
// (core/description/descriptor_encoding.h) and compared against the similarity
// threshold scaled into the same domain. Returns tree slots, which are
// indices into ModelIndex::arcs(). Allocates nothing.
class ArcSearch {
 public:
  ArcSearch() = default;
  // max_leaves: at most that many tree leaves per query (0: exact), by
  // default leaves_for() the index's parameters and model count.
  explicit ArcSearch(const ModelIndex& index);
  ArcSearch(const ModelIndex& index, int max_leaves);

  // Leaves per query for an index of `models` models built with `params`:
  // max_search_leaves, grown with the square root of models over
  // search_reference_models (at most kMaxLeavesGrowth-fold); 0: exact.
  static int leaves_for(const DescriptorParams& params, std::uint64_t models);
  // 3-fold (reached at 9 times the reference's models): 18 leaves of 8 at
  // 50 signs keep the sign benchmark's recall (14 lost 2.5 points), 24 at
  // 200 models keep the pose's support (test_search_recall) for about
  // twice the 10-model frame's cost, where 36 cost 3x (docs/RESULTS.md,
  // "The search budget at 200 models").
  static constexpr double kMaxLeavesGrowth = 3.0;
  int max_leaves() const { return max_leaves_; }
  // Changes the leaf budget (a detector's options); 0: exact.
  void set_max_leaves(int max_leaves) { max_leaves_ = max_leaves < 0 ? 0 : max_leaves; }

  DescriptorEncoding encoding() const { return encoding_; }
  // Slots of the model arcs whose descriptor is within
  // params.descriptor.similarity_threshold of q and, when `attributes` is
  // not null (core/description/arc_attributes.h) and params.graph.max_scale_error > 0,
  // whose scale attributes are each within max_scale_error of them (see
  // BasicKdTreeView::radius_search for `capacity` and the return value).
  std::uint32_t radius_search(const ArcDescriptor& q, const float* attributes, std::uint32_t* out,
                              std::uint32_t capacity) const;
  // The same for a descriptor already quantised at the index's encoding
  // scale (int16 and int8 indexes: arc_descriptor_fixed()).
  std::uint32_t radius_search_quantised(const std::int32_t* q, const float* attributes,
                                        std::uint32_t* out, std::uint32_t capacity) const;

  // A scene arc's search point in the tree's domain (integer encodings: the
  // integers, held exactly in floats) and whether its attributes are boxed:
  // kept so the arc can be compared again with single model arcs.
  struct Query {
    ArcSearchPoint point{};
    bool box = false;
  };
  Query query(const ArcDescriptor& q, const float* attributes) const;
  Query query_quantised(const std::int32_t* q, const float* attributes) const;
  std::uint32_t search(const Query& q, std::uint32_t* out, std::uint32_t capacity) const;
  // Whether search_keys() can be used: an approximate search (max_leaves()
  // > 0) of an index given at construction.
  bool writes_keys() const { return max_leaves_ > 0 && keys_.from != nullptr; }
  // The same search, writing the found arcs' keys (from << 32 | to:
  // ModelIndex::arc() of each slot search() would write) instead of their
  // slots; only when writes_keys().
  std::uint32_t search_keys(const Query& q, std::uint64_t* out, std::uint32_t capacity) const;
  // Whether the model arc in tree slot `slot` is within the similarity
  // radius and scale box of q: what search() tests, for one arc.
  bool matches(const Query& q, std::uint32_t slot) const;
  // Asks the cache for the model arc point matches() reads.
  void prefetch(std::uint32_t slot) const;

 private:
  template <class T>
  std::array<T, kSearchDims> encoded(const Query& q) const;
  std::uint32_t search_encoded(const ArcSearchPointI16& p, bool box, std::uint32_t* out,
                               std::uint32_t capacity) const;
  std::uint32_t search_encoded(const ArcSearchPointI8& p, bool box, std::uint32_t* out,
                               std::uint32_t capacity) const;

  DescriptorEncoding encoding_ = DescriptorEncoding::kFloat32;
  const ArcSearchPoint* points_f32_ = nullptr;  // tree points, by slot
  const ArcSearchPointI16* points_i16_ = nullptr;
  const ArcSearchPointI8* points_i8_ = nullptr;
  ArcTreeView f32_;
  ArcTreeView16 i16_;
  ArcTreeView8 i8_;
  float radius2_ = 0.f;              // float32
  std::int64_t radius2_scaled_ = 0;  // int16, int8
  std::int32_t box_ = 0;             // attribute box, grid steps (0: none)
  int max_leaves_ = 0;               // approximate search (0: exact)
  KdArcKeys keys_{};                 // the index's arcs by slot
};

}  // namespace kg
