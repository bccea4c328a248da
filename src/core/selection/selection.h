// Correspondence selection through keytuples (paper sections 4 and 8): for
// the scene keytuple (a, b, c) of a keygraph, the model arcs similar to
// (a, b) and to (b, c) are joined on their shared vertex, (c, a) must be
// similar to a model arc (c_m, a_m), and (a_m, b_m, c_m) must be a model
// keytuple (clockwise). Arcs and 4-circuits follow the same chain.
//
// Scene arcs are Delaunay half-edges; each is described and looked up in
// the model search tree at most once per frame, on first use, and its
// opposite half-edge reads the same model arcs reversed. A circuit's lists
// are first cut to the arcs whose ends are candidates of both their scene
// vertices (a byte of flags per model keypoint: which lists it leaves and
// enters), which drops nearly all of them; the few left are sorted by
// (from, to) (core/selection/arc_keys.h) and joined by binary searches.
// With vertex descriptors, each vertex pair of a joined correspondence must
// be similar too.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/description/arc_types.h"
#include "core/index/kdtree.h"
#include "core/keygraphs/delaunay.h"
#include "core/keygraphs/keygraph.h"
#include "core/selection/arc_adjacency.h"
#include "keygraph/detector.h"
#include "keygraph/image.h"
#include "keygraph/model_index.h"

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
  static constexpr int kMaxLeavesGrowth = 8;
  int max_leaves() const { return max_leaves_; }

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
};

struct SelectionInput {
  const ModelIndex* index = nullptr;
  const ArcSearch* search = nullptr;
  ImageView blurred;                      // scene blurred for profiles
  const Point2f* scene_points = nullptr;  // sampled scene keypoints
  // Their detector scales (sigma, pixels; 0 unknown), for
  // GraphParams::max_scale_error; nullptr skips that check.
  const float* scene_scales = nullptr;
  const Delaunay* triangulation = nullptr;
  const WorkVector<SceneKeygraph>* keygraphs = nullptr;
  // Vertex descriptors (kVertexDescriptorSize bytes) and their inverse
  // norms, of the model keypoints (global ids) and of the sampled scene
  // keypoints. When set, a correspondence is also rejected when any vertex
  // pair is farther apart than params.descriptor.vertex_threshold (paper
  // section 7).
  const std::uint8_t* model_descriptors = nullptr;
  const float* model_inverse_norms = nullptr;
  const std::uint8_t* scene_descriptors = nullptr;
  const float* scene_inverse_norms = nullptr;
  // Set (graph.complete_circuits, 3-circuits): a circuit is also selected
  // from two joined arc lists when the model arc closing it matches the
  // third scene arc, looked up here and compared directly.
  const ArcAdjacency* adjacency = nullptr;
};

class Selector {
 public:
  explicit Selector(std::pmr::memory_resource* memory = std::pmr::get_default_resource())
      : state_(memory),
        begin_(memory),
        count_(memory),
        pool_(memory),
        found_(memory),
        sort_scratch_(memory),
        kept_{WorkVector<std::uint64_t>(memory), WorkVector<std::uint64_t>(memory),
              WorkVector<std::uint64_t>(memory), WorkVector<std::uint64_t>(memory)},
        flags_(memory),
        described_(memory),
        queries_(memory),
        triples_(memory),
        chain_head_(memory),
        chain_next_(memory),
        joined_(memory),
        profile_(memory),
        sums_(memory) {}

  // Sizes the buffers for `limits` (scene keypoints, arc matches per query
  // and per frame, frame size for the profiles) and an index of
  // `model_keypoints` keypoints: select() then allocates nothing, and stops
  // looking up model arcs once limits.max_arc_pool are kept in a frame.
  // With `completion` (graph.complete_circuits), also the per-half-edge
  // queries and the completed circuits.
  void reserve(const Limits& limits, std::uint32_t model_keypoints, bool completion = false);

  // Clears and fills `matches` (at most limits.max_correspondences); updates
  // stats.arcs_described, correspondences and the truncation flags.
  void select(const SelectionInput& in, const Limits& limits, WorkVector<KeygraphMatch>& matches,
              DetectStats& stats);

  // For tests. A left-over candidate flag would only cost time (the join
  // checks every arc), so outputs cannot show one, and a left-over chain
  // head of the completion's join could rarely: with checking on,
  // select() looks at every flag and head after every keygraph, and
  // candidate_flags_clear() says whether all were clear each time.
  void set_checking(bool on) { checking_ = on; }
  bool candidate_flags_clear() const { return !flags_left_ && all_flags_clear(); }
  // Model arcs the last select() passed to its semi-join, and kept.
  std::uint64_t semi_join_arcs_in() const { return semi_join_in_; }
  std::uint64_t semi_join_arcs_kept() const { return semi_join_kept_; }

 private:
  // The model-arc keys (from << 32 | to) similar to one half-edge:
  // pool_[begin..begin + count), each to be read the other way round when
  // `reversed`.
  struct ArcList {
    std::uint32_t begin = 0;
    std::uint32_t count = 0;
    bool reversed = false;
  };
  // Half-edge e's list, looked up on first use (empty when the arc has no
  // descriptor).
  ArcList lookup(const SelectionInput& in, int e, const Limits& limits, DetectStats& stats);

  // With in.adjacency: fills triples_ with the model triples (in the scene
  // keygraph's vertex order, sorted, each once) that two of the three lists
  // join into a clockwise circuit passing `plausible`, closed by a model arc
  // that matches the third scene arc. False when more than `capacity` were
  // found before duplicates (up to one per pass) were removed: the rest are
  // dropped.
  template <class Plausible>
  bool complete_circuit(const SelectionInput& in, const SceneKeygraph& g, const ArcList* lists,
                        std::uint32_t capacity, Plausible&& plausible);

  // Fills kept_[0..k) with the arcs of lists[0..k) (a k-circuit's, in
  // order) that can close a circuit, each sorted; false when one is empty.
  bool candidate_lists(const ArcList* lists, int k);

  bool all_flags_clear() const {
    for (std::uint8_t f : flags_)
      if (f != 0) return false;
    for (std::uint32_t h : chain_head_)
      if (h != 0) return false;
    return true;
  }

  enum : std::uint8_t { kUnseen = 0, kLooked = 1, kReversed = 2 };
  WorkVector<std::uint8_t> state_;
  WorkVector<std::uint32_t> begin_;
  WorkVector<std::uint32_t> count_;
  // Model-arc keys of all lookups of the frame, unsorted: pool_[0,
  // pool_used_). The vector only grows, so a frame's look-ups write their
  // keys without zeroing them first (a resize per look-up cleared about
  // 3 MB a frame).
  WorkVector<std::uint64_t> pool_;
  std::size_t pool_used_ = 0;
  WorkVector<std::uint32_t> found_;
  WorkVector<std::uint64_t> sort_scratch_;  // one kept list (core/selection/arc_keys.h)
  WorkVector<std::uint64_t> kept_[kMaxVertices];
  std::uint32_t kept_count_[kMaxVertices] = {0, 0, 0, 0};
  WorkVector<std::uint8_t> flags_;  // per model keypoint: bit i leaves, 4 + i enters list i
  int id_bits_ = 32;                // bits of the index's keypoint ids
  // Per half-edge, with in.adjacency: whether it was described, and its query.
  WorkVector<std::uint8_t> described_;
  WorkVector<ArcSearch::Query> queries_;
  WorkVector<std::array<std::uint32_t, 3>> triples_;
  std::uint32_t triple_count_ = 0;
  // The completion's join on the shared vertex w: per model keypoint the
  // first kept arc into w (2w) and out of w (2w + 1), plus one (0: none);
  // per kept arc the next of its w (arcs into w, then arcs out of w).
  // All zero between passes.
  WorkVector<std::uint32_t> chain_head_;
  WorkVector<std::uint32_t> chain_next_;
  WorkVector<std::uint32_t> joined_;  // the shared vertices of a pass
  // The completion's funnel this frame (DetectStats::completion_*).
  std::uint64_t completion_tried_ = 0;
  std::uint64_t completion_clockwise_ = 0;
  std::uint64_t completion_plausible_ = 0;
  std::uint64_t completion_closed_ = 0;
  WorkVector<float> profile_;
  WorkVector<std::int32_t> sums_;  // fixed-point profiles
  std::size_t pool_limit_ = static_cast<std::size_t>(-1);
  bool checking_ = false;
  bool flags_left_ = false;
  std::uint64_t semi_join_in_ = 0;
  std::uint64_t semi_join_kept_ = 0;
};

}  // namespace kg
