// Correspondence selection through keytuples (paper sections 4 and 8): for
// the scene keytuple (a, b, c) of a keygraph, the model arcs similar to
// (a, b) and to (b, c) are joined on their shared vertex, (c, a) must be
// similar to a model arc (c_m, a_m), and (a_m, b_m, c_m) must be a model
// keytuple (clockwise). Arcs and 4-circuits follow the same chain.
//
// Scene arcs are Delaunay half-edges, described beforehand
// (core/description/scene_arcs.h); each is looked up in the model search
// tree at most once per frame, on first use, and its opposite half-edge
// reads the same model arcs reversed. A circuit's lists
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
#include "core/description/scene_arcs.h"
#include "core/index/arc_search.h"
#include "core/keygraphs/delaunay.h"
#include "core/keygraphs/keygraph.h"
#include "core/selection/arc_adjacency.h"
#include "keygraph/detector.h"
#include "keygraph/image.h"
#include "keygraph/model_index.h"

namespace kg {

struct SelectionInput {
  const ModelIndex* index = nullptr;
  // The index's parameters with the detector's options applied.
  const Params* params = nullptr;
  // Per model, 0 when its correspondences are dropped (DetectOptions::
  // models); nullptr keeps every model's.
  const std::uint8_t* model_searched = nullptr;
  const ArcSearch* search = nullptr;
  const Point2f* scene_points = nullptr;  // sampled scene keypoints
  const Delaunay* triangulation = nullptr;
  // The scene arcs' queries (core/description/scene_arcs.h); the selection
  // asks it for an arc its description stage left to the other direction.
  SceneArcs* arcs = nullptr;
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
        triples_(memory),
        chain_head_(memory),
        chain_next_(memory),
        joined_(memory) {}

  // Sizes the buffers for `limits` (scene keypoints, arc matches per query
  // and per frame, frame size for the profiles) and an index of
  // `model_keypoints` keypoints: select() then allocates nothing, and stops
  // looking up model arcs once limits.max_arc_pool are kept in a frame.
  // With `completion` (graph.complete_circuits), also the per-half-edge
  // queries and the completed circuits.
  void reserve(const Limits& limits, std::uint32_t model_keypoints, bool completion = false);

  // Clears and fills `matches` (at most limits.max_correspondences); updates
  // stats.correspondences and the truncation flags.
  void select(const SelectionInput& in, const Limits& limits, WorkVector<KeygraphMatch>& matches,
              DetectStats& stats);

  // Whether the join's per-model-keypoint state (the candidate flags and
  // the completion's chain heads) is all clear, as select() leaves it after
  // every keygraph and as the next keygraph needs it: a flag left set would
  // only cost time (the join checks every arc), so no output shows one.
  bool join_state_clear() const { return all_flags_clear(); }

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
  std::size_t pool_limit_ = static_cast<std::size_t>(-1);
  std::uint64_t semi_join_in_ = 0;
  std::uint64_t semi_join_kept_ = 0;
};

}  // namespace kg
