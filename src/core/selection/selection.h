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
#include <atomic>
#include <chrono>
#include <cstdint>
#include <vector>

#include "core/description/arc_types.h"
#include "core/description/scene_arcs.h"
#include "core/index/arc_search.h"
#include "core/keygraphs/delaunay.h"
#include "core/keygraphs/keygraph.h"
#include "core/selection/arc_adjacency.h"
#include "core/support/worker_pool.h"
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
  // Threads for the look-ups and joins (with circuit completion); nullptr:
  // the caller's only.
  WorkerPool* workers = nullptr;
  // The frame's time budget (DetectOptions::time_budget_ms): the look-ups
  // and joins stop once the steady clock passes it; nullptr: none.
  const std::chrono::steady_clock::time_point* deadline = nullptr;
};

class Selector {
 public:
  explicit Selector(std::pmr::memory_resource* memory = std::pmr::get_default_resource());

  // Sizes the buffers for `limits` (scene keypoints, arc matches per query
  // and per frame, correspondences, threads) and `index`, and notes each of
  // its keypoints' model: select() then allocates nothing, and stops
  // looking up model arcs once limits.max_arc_pool are kept in a frame.
  // select() must be given the same index. With `completion`
  // (graph.complete_circuits), also the completed circuits. With fill false
  // (Detector::workspace_bytes' measuring pass) only counts: nothing is
  // written into the memory.
  void reserve(const Limits& limits, const ModelIndex& index, bool completion = false,
               bool fill = true);

  // Clears and fills `matches` (at most limits.max_correspondences); updates
  // stats' selection counts and truncation flags. With circuit completion
  // and in.workers, the look-ups and the joins run on the workers; the
  // output is the same for any number of them.
  void select(const SelectionInput& in, const Limits& limits, WorkVector<KeygraphMatch>& matches,
              DetectStats& stats);

  // Whether the join's per-model-keypoint state (the candidate flags and
  // the completion's chain heads) is all clear, as select() leaves it after
  // every keygraph and as the next keygraph needs it: a flag left set would
  // only cost time (the join checks every arc), so no output shows one.
  bool join_state_clear() const;
  // Whether the last select() stopped at in.deadline.
  bool ran_out_of_time() const { return out_of_time_.load(std::memory_order_relaxed); }

 private:
  // The model-arc keys (from << 32 | to) similar to one half-edge:
  // pool_[begin..begin + count), each to be read the other way round when
  // `reversed`.
  struct ArcList {
    std::uint32_t begin = 0;
    std::uint32_t count = 0;
    bool reversed = false;
  };

  // One thread's state of the join: the candidate flags (a byte per model
  // keypoint: bit i leaves, 4 + i enters list i), the kept lists, the
  // completion's chains and triples, its counters, and its correspondences
  // (threads other than the caller's; in keygraph order, with the chunks
  // they came from).
  struct JoinScratch {
    explicit JoinScratch(std::pmr::memory_resource* memory);
    WorkVector<std::uint32_t> found;         // one search's tree slots
    WorkVector<std::uint64_t> sort_scratch;  // one kept list (core/selection/arc_keys.h)
    WorkVector<std::uint64_t> kept[kMaxVertices];
    std::uint32_t kept_count[kMaxVertices] = {0, 0, 0, 0};
    WorkVector<std::uint8_t> flags;  // without completion
    // With completion: per model keypoint the stamp of the last set it was
    // put in (complete_circuit), and the last stamp handed out.
    WorkVector<std::uint8_t> marks;
    std::uint8_t mark = 0;
    WorkVector<std::array<std::uint32_t, 3>> triples;
    std::uint32_t triple_count = 0;
    // The completion's join on the shared vertex w: per model keypoint the
    // first kept arc into w (2w) and out of w (2w + 1), plus one (0: none);
    // per kept arc the next of its w (arcs into w, then arcs out of w).
    // All zero between passes.
    WorkVector<std::uint32_t> chain_head;
    WorkVector<std::uint32_t> chain_next;
    WorkVector<std::uint32_t> joined;  // the shared vertices of a pass
    WorkVector<KeygraphMatch> out;
    // This frame's counts (DetectStats' selection counts).
    std::uint64_t completion_tried = 0, completion_clockwise = 0;
    std::uint64_t completion_plausible = 0, completion_closed = 0;
    std::uint64_t semi_join_in = 0, semi_join_kept = 0;
    std::uint64_t vertex_rejections = 0;
    bool truncated_completion = false;  // a keygraph's circuits beyond their capacity
    void clear_counts();
  };
  // A run of keygraphs joined by one thread: where its correspondences
  // went in that thread's JoinScratch::out, and whether the output was
  // full before the run ended.
  struct Chunk {
    int worker = 0;
    std::uint32_t begin = 0, end = 0;
    bool full = false;
    bool truncated_completion = false;
  };

  // Half-edge e's list, looked up on first use (empty when the arc has no
  // descriptor): the selection without circuit completion, one thread.
  ArcList lookup(const SelectionInput& in, int e, const Limits& limits, DetectStats& stats,
                 JoinScratch& s);
  // With circuit completion every arc of every keygraph is looked up, so
  // all are looked up first (search_chosen, the described direction of
  // each edge, in the description's order), and list_of() reads them.
  void search_chosen(const SelectionInput& in, const Limits& limits, DetectStats& stats);
  ArcList list_of(const SelectionInput& in, int e) const;
  // Searches half-edge e into the pool at `at` (room for `capacity` keys);
  // returns the keys written, `total` the arcs found.
  std::uint32_t search_into(const SelectionInput& in, int e, JoinScratch& s, std::uint64_t* at,
                            std::uint32_t capacity, std::uint32_t& total) const;

  // Joins keygraphs [first, last) into s.out (or `out`), `lists` giving each
  // half-edge's list; false when the output filled up (limits.
  // max_correspondences).
  template <class Lists>
  bool join(const SelectionInput& in, const Limits& limits, const SceneKeygraph* first,
            const SceneKeygraph* last, JoinScratch& js, WorkVector<KeygraphMatch>& out,
            Lists&& list_for);

  // With in.adjacency: fills s.triples with the model triples (in the
  // scene keygraph's vertex order, sorted, each once) that two of the three
  // lists join into a clockwise circuit passing `plausible`, closed by a
  // model arc that matches the third scene arc. False when more than
  // `capacity` were found before duplicates (up to one per pass) were
  // removed: the rest are dropped.
  template <class Plausible>
  bool complete_circuit(const SelectionInput& in, const SceneKeygraph& g, const ArcList* lists,
                        std::uint32_t capacity, JoinScratch& js, Plausible&& plausible);

  // Fills s.kept[0..k) with the arcs of lists[0..k) (a k-circuit's, in
  // order) that can close a circuit, each sorted; false when one is empty.
  bool candidate_lists(const ArcList* lists, int k, JoinScratch& js);

  // A stamp no model keypoint's mark holds yet.
  static std::uint8_t next_mark(JoinScratch& js);

  // Per-thread scratch sized for the frame (within reserve()'s capacity).
  void prepare(JoinScratch& s, const SelectionInput& in, const Limits& limits, bool completion);

  enum : std::uint8_t { kUnseen = 0, kLooked = 1, kReversed = 2 };
  std::pmr::memory_resource* memory_;
  WorkVector<std::uint8_t> state_;
  WorkVector<std::uint32_t> begin_;
  WorkVector<std::uint32_t> count_;
  WorkVector<std::uint32_t> total_;  // arcs found per half-edge (search_chosen)
  // Room for keys from a memory resource, never initialised: a frame's
  // look-ups write every key the joins read. (A vector's resize to the
  // pool's 2 M keys zeroed 16 MB on the first frame: 17 M instructions and
  // its page faults, about 7 % of a first 640x480 frame.)
  class KeyStorage {
   public:
    explicit KeyStorage(std::pmr::memory_resource* memory) : memory_(memory) {}
    KeyStorage(const KeyStorage&) = delete;
    KeyStorage& operator=(const KeyStorage&) = delete;
    ~KeyStorage() { release(); }
    // Room for at least n keys (their values are not kept).
    void reserve(std::size_t n);
    std::uint64_t* data() const { return keys_; }
    std::size_t capacity() const { return capacity_; }

   private:
    void release();
    std::pmr::memory_resource* memory_;
    std::uint64_t* keys_ = nullptr;
    std::size_t capacity_ = 0;
  };
  // Model-arc keys of all lookups of the frame, unsorted: pool_[0,
  // pool_used_), at most pool_limit_ (reserve(): Limits::max_arc_pool).
  KeyStorage pool_;
  std::size_t pool_used_ = 0;
  std::size_t pool_limit_ = 0;
  int id_bits_ = 32;  // bits of the index's keypoint ids
  // Per model keypoint its model (reserve(); empty for an index of more
  // than 65536 models, whose keypoints ask ModelIndex::model_of_keypoint),
  // and per model half the smallest area scale of its views (select(), for
  // the frame's parameters): the join asks both for every candidate, and a
  // binary search over the model records was most of what it paid for them.
  WorkVector<std::uint16_t> owners_;
  WorkVector<float> min_areas_;
  // One per thread (Limits::threads), the caller's first.
  WorkVector<JoinScratch> scratch_;
  WorkVector<Chunk> chunks_;
  std::atomic<bool> out_of_time_{false};
};

}  // namespace kg
