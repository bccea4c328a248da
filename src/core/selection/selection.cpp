#include "core/selection/selection.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <type_traits>

#include "core/description/arc_attributes.h"
#include "core/description/arc_descriptor.h"
#include "core/description/arc_types.h"
#include "core/description/descriptor_encoding.h"
#include "core/description/vertex_descriptor.h"
#include "core/index/index_internals.h"
#include "core/pose/homography.h"
#include "core/sampling/sampling.h"
#include "core/selection/arc_keys.h"

namespace kg {
namespace {

// Whether the model -> scene map of a correspondence is a plausible local
// distortion (GraphParams::max_anisotropy): the affine map through the
// first three vertices, or the length ratio for arcs.
bool plausible_local_map(const Point2f* m, const Point2f* s, int k, const Params& params,
                         float min_area) {
  const float max_aniso = params.graph.max_anisotropy;
  if (max_aniso <= 0.f) return true;
  const float max_area = 2.f * static_cast<float>(params.ransac.max_scale_change);
  if (k == 2) {
    const float lm = std::hypot(m[1].x - m[0].x, m[1].y - m[0].y);
    const float ls = std::hypot(s[1].x - s[0].x, s[1].y - s[0].y);
    const float r2 = (ls * ls) / (lm * lm);
    return r2 >= min_area && r2 <= max_area;
  }
  // A = S M^-1 with M, S the edge matrices of the two triangles.
  const float m00 = m[1].x - m[0].x, m01 = m[2].x - m[0].x, m10 = m[1].y - m[0].y,
              m11 = m[2].y - m[0].y;
  const float s00 = s[1].x - s[0].x, s01 = s[2].x - s[0].x, s10 = s[1].y - s[0].y,
              s11 = s[2].y - s[0].y;
  const float det_m = m00 * m11 - m01 * m10;
  if (det_m == 0.f) return false;
  const float inv = 1.f / det_m;
  const float a = (s00 * m11 - s01 * m10) * inv, b = (-s00 * m01 + s01 * m00) * inv;
  const float c = (s10 * m11 - s11 * m10) * inv, d = (-s10 * m01 + s11 * m00) * inv;
  const float det = a * d - b * c;  // area scale
  if (!(det >= min_area && det <= max_area)) return false;
  // sigma1 / sigma2 from the Frobenius norm and the determinant.
  const float f2 = a * a + b * b + c * c + d * d;
  const float disc = std::sqrt(std::max(0.f, f2 * f2 - 4.f * det * det));
  const float s1 = (f2 + disc) * 0.5f, s2 = (f2 - disc) * 0.5f;  // squared singular values
  return s2 > 0.f && s1 <= max_aniso * max_aniso * s2;
}

// Sets marks[end_of(keys[x])] = mark for x < n. Four keys a round: the
// loop's own counting was half of these loops' instructions.
template <class End>
inline void mark_ends(const std::uint64_t* keys, std::uint32_t n, End end_of, std::uint8_t* marks,
                      std::uint8_t mark) {
  std::uint32_t x = 0;
  for (; x + 4 <= n; x += 4) {
    marks[end_of(keys[x])] = mark;
    marks[end_of(keys[x + 1])] = mark;
    marks[end_of(keys[x + 2])] = mark;
    marks[end_of(keys[x + 3])] = mark;
  }
  for (; x < n; ++x) marks[end_of(keys[x])] = mark;
}

// Copies to `out` the keys of keys[0..n) whose end_of() carries `mark`, in
// order; returns how many. Branch-free (few are kept), four keys a round,
// each round's marks read before its stores (a byte store may alias them).
template <class End>
inline std::uint32_t keep_marked(const std::uint64_t* keys, std::uint32_t n, End end_of,
                                 const std::uint8_t* marks, std::uint8_t mark, std::uint64_t* out) {
  std::uint32_t kept = 0, x = 0;
  for (; x + 4 <= n; x += 4) {
    const std::uint64_t k0 = keys[x], k1 = keys[x + 1], k2 = keys[x + 2], k3 = keys[x + 3];
    const auto t0 = static_cast<std::uint32_t>(marks[end_of(k0)] == mark);
    const auto t1 = static_cast<std::uint32_t>(marks[end_of(k1)] == mark);
    const auto t2 = static_cast<std::uint32_t>(marks[end_of(k2)] == mark);
    const auto t3 = static_cast<std::uint32_t>(marks[end_of(k3)] == mark);
    out[kept] = k0;
    kept += t0;
    out[kept] = k1;
    kept += t1;
    out[kept] = k2;
    kept += t2;
    out[kept] = k3;
    kept += t3;
  }
  for (; x < n; ++x) {
    out[kept] = keys[x];
    kept += static_cast<std::uint32_t>(marks[end_of(keys[x])] == mark);
  }
  return kept;
}

}  // namespace

std::uint8_t Selector::next_mark(JoinScratch& js) {
  if (++js.mark == 0) {
    // Wrapped (every 255 stamps, a few dozen keygraphs): no mark may
    // still hold a stamp about to be reused. Bytes keep the marks as small
    // in the cache as the flags were; 16-bit stamps saved the wraps but
    // missed the cache a third more often (docs/RESULTS.md, "Frame cost cut").
    std::fill(js.marks.begin(), js.marks.end(), std::uint8_t{0});
    js.mark = 1;
  }
  return js.mark;
}

Selector::JoinScratch::JoinScratch(std::pmr::memory_resource* memory)
    : found(memory),
      sort_scratch(memory),
      kept{WorkVector<std::uint64_t>(memory), WorkVector<std::uint64_t>(memory),
           WorkVector<std::uint64_t>(memory), WorkVector<std::uint64_t>(memory)},
      flags(memory),
      marks(memory),
      triples(memory),
      chain_head(memory),
      chain_next(memory),
      joined(memory),
      out(memory) {}

void Selector::JoinScratch::clear_counts() {
  completion_tried = completion_clockwise = completion_plausible = completion_closed = 0;
  semi_join_in = semi_join_kept = vertex_rejections = 0;
  truncated_completion = false;
}

void Selector::KeyStorage::reserve(std::size_t n) {
  if (n <= capacity_) return;
  release();
  keys_ = static_cast<std::uint64_t*>(
      memory_->allocate(n * sizeof(std::uint64_t), alignof(std::uint64_t)));
  capacity_ = n;
}

void Selector::KeyStorage::release() {
  if (keys_ != nullptr)
    memory_->deallocate(keys_, capacity_ * sizeof(std::uint64_t), alignof(std::uint64_t));
  keys_ = nullptr;
  capacity_ = 0;
}

Selector::Selector(std::pmr::memory_resource* memory)
    : memory_(memory),
      state_(memory),
      begin_(memory),
      count_(memory),
      total_(memory),
      pool_(memory),
      owners_(memory),
      min_areas_(memory),
      scratch_(memory),
      chunks_(memory) {}

namespace {

// Keygraph runs per thread in the parallel join: enough that a thread
// finishing early takes another (the work of a run follows the objects in
// the frame), few enough that claiming them costs nothing.
constexpr int kChunksPerThread = 8;

}  // namespace

void Selector::reserve(const Limits& limits, const ModelIndex& index, bool completion, bool fill) {
  const std::uint32_t model_keypoints = index.keypoint_count();
  const auto models = static_cast<std::size_t>(index.model_count());
  min_areas_.reserve(models);
  owners_.clear();
  if (models <= std::size_t{1} << 16) {
    owners_.reserve(model_keypoints);
    if (fill) {
      for (int m = 0; m < index.model_count(); ++m) {
        const ModelInfo info = index.model(m);
        owners_.resize(info.keypoint_begin + std::size_t{info.keypoint_count},
                       static_cast<std::uint16_t>(m));
      }
    }
  }
  const auto half_edges = 6 * static_cast<std::size_t>(std::max(0, limits.max_scene_keypoints));
  state_.reserve(half_edges);
  begin_.reserve(half_edges);
  count_.reserve(half_edges);
  if (completion) total_.reserve(half_edges);
  pool_limit_ = static_cast<std::size_t>(std::max(0, limits.max_arc_pool));
  pool_.reserve(pool_limit_);
  const auto per_query = static_cast<std::size_t>(std::max(0, limits.max_arc_matches));
  // Threads other than the caller's join with circuit completion only.
  const int threads = completion ? std::max(1, limits.threads) : 1;
  scratch_.reserve(static_cast<std::size_t>(threads));
  scratch_.clear();
  for (int t = 0; t < threads; ++t) {
    // The measuring pass (fill false) must not write into its placeholder
    // memory: a scratch on the stack stands in for each, its buffers
    // counted all the same.
    JoinScratch stand_in(memory_);
    JoinScratch& s = fill ? scratch_.emplace_back(memory_) : stand_in;
    s.found.reserve(per_query);
    s.sort_scratch.reserve(per_query);
    for (WorkVector<std::uint64_t>& kept : s.kept) kept.reserve(per_query);
    // The flags serve the join without completion, the marks the join with.
    if (completion)
      s.marks.reserve(model_keypoints);
    else
      s.flags.reserve(model_keypoints);
    if (completion) {
      s.triples.reserve(3 * per_query);  // a circuit is found by up to 3 passes before dedupe
      s.chain_head.reserve(2 * static_cast<std::size_t>(model_keypoints));
      s.chain_next.reserve(2 * per_query);
      s.joined.reserve(per_query);
    }
    if (threads > 1)
      s.out.reserve(static_cast<std::size_t>(std::max(0, limits.max_correspondences)));
  }
  if (threads > 1) chunks_.reserve(static_cast<std::size_t>(threads * kChunksPerThread));
}

void Selector::prepare(JoinScratch& s, const SelectionInput& in, const Limits& limits,
                       bool completion) {
  // Within what reserve() sized (the Detector's limits and index), this
  // never allocates.
  const auto per_query = static_cast<std::size_t>(std::max(0, limits.max_arc_matches));
  if (s.found.size() < per_query) s.found.resize(per_query);
  if (s.sort_scratch.size() < per_query) s.sort_scratch.resize(per_query);
  for (WorkVector<std::uint64_t>& kept : s.kept)
    if (kept.size() < per_query) kept.resize(per_query);
  if (completion) {
    // Stamps carry over from frame to frame; set once per index size.
    if (s.marks.size() != in.index->keypoint_count()) {
      s.marks.assign(in.index->keypoint_count(), 0);
      s.mark = 0;
    }
  } else {
    // All clear between keygraphs (candidate_lists() clears what it flags).
    s.flags.assign(in.index->keypoint_count(), 0);
  }
  if (completion) {
    if (s.triples.size() < 3 * per_query) s.triples.resize(3 * per_query);
    if (s.chain_next.size() < 2 * per_query) s.chain_next.resize(2 * per_query);
    if (s.joined.size() < per_query) s.joined.resize(per_query);
    // All zero between passes: set once per index size.
    const std::size_t heads = 2 * static_cast<std::size_t>(in.index->keypoint_count());
    if (s.chain_head.size() != heads) s.chain_head.assign(heads, 0);
  }
  s.out.clear();
  s.clear_counts();
}

std::uint32_t Selector::search_into(const SelectionInput& in, int e, JoinScratch& s,
                                    std::uint64_t* at, std::uint32_t capacity,
                                    std::uint32_t& total) const {
  const ArcSearch::Query& query = in.arcs->query(e);
  const auto cap = static_cast<std::uint32_t>(s.found.size());
  if (in.search->writes_keys()) {
    // The tree writes the keys as it scans each leaf (the same keys, in
    // the same order, as the conversion of its slots below).
    total = in.search->search_keys(query, at, std::min(cap, capacity));
    return std::min({total, cap, capacity});
  }
  total = in.search->search(query, s.found.data(), cap);
  const std::uint32_t n = std::min({total, cap, capacity});
  const std::uint32_t* slots = s.found.data();
  for (std::uint32_t i = 0; i < n; ++i) IndexInternals::prefetch_arc(*in.index, slots[i]);
  for (std::uint32_t i = 0; i < n; ++i) {
    const ModelArc arc = in.index->arc(slots[i]);
    at[i] = arc_key(arc.from, arc.to);
  }
  return n;
}

Selector::ArcList Selector::lookup(const SelectionInput& in, int e, const Limits& limits,
                                   DetectStats& stats, JoinScratch& s) {
  if (state_[e] != kUnseen) return {begin_[e], count_[e], state_[e] == kReversed};
  state_[e] = kLooked;
  begin_[e] = static_cast<std::uint32_t>(pool_used_);
  count_[e] = 0;
  // The reverse arc b -> a was looked up already: model arcs similar to it
  // are, reversed, the ones similar to a -> b (reversing a profile maps its
  // descriptor by x -> e^{2 pi i x / l} conj(F(x)), a Euclidean isometry,
  // and the model holds both directions of every arc), so read its keys
  // the other way round instead of describing and searching again. Only
  // arcs within one quantisation step of the threshold can differ.
  const int opposite = in.triangulation->halfedges()[e];
  if (opposite >= 0 && state_[opposite] == kLooked) {
    state_[e] = kReversed;
    begin_[e] = begin_[opposite];
    count_[e] = count_[opposite];
    return {begin_[e], count_[e], true};
  }
  // The arc was described by the description stage, or its opposite was
  // and the selection reaches this direction first (without circuit
  // completion only; core/description/scene_arcs.h).
  SceneArcs& arcs = *in.arcs;
  if (!arcs.chosen(e)) arcs.describe_now(e);
  if (!arcs.described(e)) return {begin_[e], 0, false};
  const std::size_t room = pool_limit_ - std::min(pool_limit_, pool_used_);
  const auto cap = static_cast<std::uint32_t>(std::max(0, limits.max_arc_matches));
  const std::size_t most = std::min<std::size_t>(cap, room);  // within the reserved pool
  std::uint32_t total = 0;
  const std::uint32_t n =
      search_into(in, e, s, pool_.data() + pool_used_, static_cast<std::uint32_t>(most), total);
  stats.arc_matches += total;
  if (n < total) stats.truncated_arc_matches = true;
  pool_used_ += n;
  count_[e] = n;
  return {begin_[e], n, false};
}

void Selector::search_chosen(const SelectionInput& in, const Limits& limits, DetectStats& stats) {
  const int* order = in.arcs->chosen_order().data();
  const int n = static_cast<int>(in.arcs->chosen_order().size());
  const auto cap = static_cast<std::uint32_t>(std::max(0, limits.max_arc_matches));
  constexpr int kBlock = 16;
  auto past_deadline = [&]() {
    if (in.deadline == nullptr || std::chrono::steady_clock::now() <= *in.deadline) return false;
    out_of_time_.store(true, std::memory_order_relaxed);
    return true;
  };
  // The lists as one thread finds them: in order, each written straight
  // into the pool and cut to its room. Once the pool is full the arcs left
  // are not searched (their lists would be empty: a frame of a large index
  // searched them all again only to count what they would have found).
  auto search_in_order = [&]() {
    JoinScratch& s = scratch_[0];
    pool_used_ = 0;
    bool stopped = false;
    for (int i = 0; i < n; ++i) {
      const int e = order[i];
      begin_[e] = static_cast<std::uint32_t>(pool_used_);
      count_[e] = total_[e] = 0;
      if (!stopped && i % kBlock == 0) stopped = past_deadline();
      if (stopped) continue;  // unsearched, as the parallel blocks leave them
      state_[e] = kLooked;
      if (!in.arcs->described(e)) continue;
      const std::size_t room = pool_limit_ - pool_used_;
      if (room == 0) {
        stats.truncated_arc_matches = true;
        continue;
      }
      std::uint32_t total = 0;
      const std::uint32_t found =
          search_into(in, e, s, pool_.data() + pool_used_,
                      static_cast<std::uint32_t>(std::min<std::size_t>(cap, room)), total);
      count_[e] = found;
      total_[e] = total;
      pool_used_ += found;
    }
  };
  if (in.workers == nullptr || in.workers->threads() <= 1) {
    search_in_order();
  } else {
    // Every thread searches a share of the chosen arcs and takes its room
    // in the pool as it goes. Lists are read by (begin, count), so where
    // each lands does not matter; only a frame whose arcs overflow the pool
    // depends on the order, and is searched again in order, as one thread
    // finds them.
    std::atomic<std::size_t> next{0};
    std::atomic<bool> overflow{false};
    auto search_block = [&](int block, int worker) {
      if (past_deadline()) return;
      JoinScratch& s = scratch_[static_cast<std::size_t>(worker)];
      const int end = std::min(n, (block + 1) * kBlock);
      for (int i = block * kBlock; i < end; ++i) {
        const int e = order[i];
        state_[e] = kLooked;
        count_[e] = 0;
        total_[e] = 0;
        if (!in.arcs->described(e) || overflow.load(std::memory_order_relaxed)) continue;
        std::uint32_t total = 0;
        const std::uint32_t found = search_into(in, e, s, s.sort_scratch.data(), cap, total);
        const std::size_t at = next.fetch_add(found, std::memory_order_relaxed);
        if (at + found > pool_limit_) {
          overflow.store(true, std::memory_order_relaxed);
          continue;
        }
        std::copy_n(s.sort_scratch.data(), found, pool_.data() + at);
        begin_[e] = static_cast<std::uint32_t>(at);
        count_[e] = found;
        total_[e] = total;
      }
    };
    const int blocks = (n + kBlock - 1) / kBlock;
    in.workers->run(blocks, search_block);
    if (overflow.load()) {
      std::fill(state_.begin(), state_.end(), kUnseen);
      search_in_order();
    } else {
      pool_used_ = next.load();
    }
  }
  for (int i = 0; i < n; ++i) {
    const int e = order[i];
    if (state_[e] != kLooked) continue;  // left unsearched by the time budget
    stats.arc_matches += total_[e];
    if (count_[e] < total_[e]) stats.truncated_arc_matches = true;
  }
}

Selector::ArcList Selector::list_of(const SelectionInput& in, int e) const {
  if (state_[e] == kLooked) return {begin_[e], count_[e], false};
  const int opposite = in.triangulation->halfedges()[e];
  if (opposite >= 0 && state_[opposite] == kLooked)
    return {begin_[opposite], count_[opposite], true};
  return {};
}

bool Selector::candidate_lists(const ArcList* lists, int k, JoinScratch& js) {
  // A semi-join: list i is cut to the arcs u -> v where u is the target of
  // an arc kept in list i - 1 (of the whole last list, for list 0) and v
  // the source of one in list i + 1 (whole; of kept list 0, for the last).
  // Flags per model keypoint say which lists it leaves (bit i) and enters
  // (bit 4 + i); each pass clears what it no longer needs, so the flags are
  // all clear again on return.
  std::uint8_t* const flags = js.flags.data();
  const int last = k - 1;
  auto leaves = [](int i) { return static_cast<std::uint8_t>(1u << i); };
  auto enters = [](int i) { return static_cast<std::uint8_t>(16u << i); };
  // List i's keys and the rotation (0 or 32 bits) that makes them
  // (from << 32 | to), held in locals: the flag stores may alias anything.
  const std::uint64_t* keys[kMaxVertices] = {nullptr, nullptr, nullptr, nullptr};
  std::uint32_t count[kMaxVertices] = {0, 0, 0, 0};
  int shift[kMaxVertices] = {0, 0, 0, 0};
  for (int i = 0; i <= last; ++i) {
    keys[i] = pool_.data() + lists[i].begin;
    count[i] = lists[i].count;
    shift[i] = lists[i].reversed ? 32 : 0;
    js.semi_join_in += count[i];
  }
  auto arc = [](std::uint64_t key, int s) { return (key >> s) | (key << ((64 - s) & 63)); };
  auto clear = [flags](const std::uint64_t* list, std::uint32_t n) {
    for (std::uint32_t x = 0; x < n; ++x) {
      flags[key_from(list[x])] = 0;  // both ends: the rotation does not matter
      flags[key_to(list[x])] = 0;
    }
  };
  // The sources of lists 1..last, and the targets of the last list.
  for (int i = 1; i <= last; ++i) {
    const std::uint64_t* list = keys[i];
    const std::uint32_t n = count[i];
    const int s = shift[i];
    const std::uint8_t from_bit = leaves(i);
    const bool targets = i == last;
    for (std::uint32_t x = 0; x < n; ++x) {
      const std::uint64_t a = arc(list[x], s);
      flags[key_from(a)] |= from_bit;
      if (targets) flags[key_to(a)] |= enters(last);
    }
  }
  for (int i = 0; i <= last; ++i) {
    const std::uint8_t entered = enters(i == 0 ? last : i - 1);
    const std::uint8_t left = leaves(i == last ? 0 : i + 1);
    // List i's own bits, no longer tested once it is cut (list 0 has none yet).
    const auto keep_at_from = static_cast<std::uint8_t>(i == 0 ? 0xFF : ~leaves(i));
    const auto keep_at_to = static_cast<std::uint8_t>(i == last ? ~enters(last) : 0xFF);
    const std::uint64_t* list = keys[i];
    const std::uint32_t total = count[i];
    const int s = shift[i];
    std::uint64_t* const out = js.kept[i].data();
    // Branch-free: most arcs are dropped. Only list 0's sources and the
    // middle lists' targets keep their flags: those loops skip the store.
    const auto cut = [&](auto clear_from, auto clear_to) {
      std::uint32_t kept = 0;
      for (std::uint32_t x = 0; x < total; ++x) {
        const std::uint64_t a = arc(list[x], s);
        const std::uint32_t from = key_from(a), to = key_to(a);
        out[kept] = a;
        kept +=
            static_cast<std::uint32_t>(((flags[from] & entered) != 0) & ((flags[to] & left) != 0));
        if constexpr (decltype(clear_from)::value) flags[from] &= keep_at_from;
        if constexpr (decltype(clear_to)::value) flags[to] &= keep_at_to;
      }
      return kept;
    };
    using Yes = std::true_type;
    using No = std::false_type;
    const std::uint32_t n = i == 0      ? (i == last ? cut(No{}, Yes{}) : cut(No{}, No{}))
                            : i == last ? cut(Yes{}, Yes{})
                                        : cut(Yes{}, No{});
    js.kept_count[i] = n;
    js.semi_join_kept += n;
    if (n == 0) {
      // No circuit: clear the later lists' bits and the kept lists' marks.
      for (int j = i + 1; j <= last; ++j) clear(keys[j], count[j]);
      for (int j = 0; j < i; ++j) clear(js.kept[j].data(), js.kept_count[j]);
      return false;
    }
    // What the next lists test of this one.
    if (i < last) {
      const std::uint8_t to_bit = enters(i);
      for (std::uint32_t x = 0; x < n; ++x) {
        if (i == 0) flags[key_from(out[x])] |= leaves(0);
        flags[key_to(out[x])] |= to_bit;
      }
    }
  }
  for (int j = 0; j < last; ++j) clear(js.kept[j].data(), js.kept_count[j]);
  for (int i = 0; i <= last; ++i) {
    sort_arc_keys(js.kept[i].data(), js.sort_scratch.data(), js.kept_count[i], id_bits_);
    // Views store one keypoint pair once per view that describes it
    // differently; a pair found twice would select its circuits twice.
    std::uint64_t* sorted = js.kept[i].data();
    js.kept_count[i] =
        static_cast<std::uint32_t>(std::unique(sorted, sorted + js.kept_count[i]) - sorted);
  }
  return true;
}

template <class Plausible>
bool Selector::complete_circuit(const SelectionInput& in, const SceneKeygraph& g,
                                const ArcList* lists, std::uint32_t capacity, JoinScratch& js,
                                Plausible&& plausible) {
  // Each pair of consecutive lists (a -> b, b -> c) is joined on b by a
  // semi-join, as candidate_lists() does for all three, with a stamp per
  // model keypoint instead of flags: a keypoint is in a set when its mark
  // is the set's stamp, so no pass clears what it marked (clearing was a
  // third of the semi-joins' loops). The closing arc c -> a is then looked
  // up in the model and compared with the scene arc.
  std::uint8_t* const marks = js.marks.data();
  const Point2f* model_points = in.index->keypoints();
  const int* opposite = in.triangulation->halfedges().data();
  js.triple_count = 0;
  bool room = true;
  for (int p = 0; p < 3 && room; ++p) {
    // Copies: the flag stores (bytes) may alias anything, so through a
    // reference the counts would be reloaded on every iteration.
    const ArcList first = lists[p];
    const ArcList second = lists[(p + 1) % 3];
    if (first.count == 0 || second.count == 0) continue;
    // The closing scene arc's query: its own, or its opposite's, which
    // matches the model arcs of the other direction.
    int closing = g.edges[(p + 2) % 3];
    bool flip = false;
    if (!in.arcs->described(closing)) {
      closing = opposite[closing];
      if (closing < 0 || !in.arcs->described(closing)) continue;
      flip = true;
    }
    const ArcSearch::Query& query = in.arcs->query(closing);
    const std::uint64_t* a_keys = pool_.data() + first.begin;
    const std::uint64_t* b_keys = pool_.data() + second.begin;
    std::uint64_t* const ka = js.kept[0].data();
    std::uint64_t* const kb = js.kept[1].data();
    std::uint32_t na = 0, nb = 0;
    // The semi-join with each list's direction known at compile time: a
    // reversed key's ends are read in place, and only the few arcs kept are
    // turned round (a rotation per arc read was a fifth of the loops).
    auto semi_join = [&](auto a_reversed, auto b_reversed) {
      constexpr bool kRa = decltype(a_reversed)::value, kRb = decltype(b_reversed)::value;
      auto b_from = [](std::uint64_t k) { return kRb ? key_to(k) : key_from(k); };
      auto a_to = [](std::uint64_t k) { return kRa ? key_from(k) : key_to(k); };
      auto turn = [](std::uint64_t* keys, std::uint32_t n) {
        for (std::uint32_t x = 0; x < n; ++x) keys[x] = (keys[x] >> 32) | (keys[x] << 32);
      };
      // The sources of the second list; the first list's arcs into them.
      const std::uint8_t sources = next_mark(js);
      mark_ends(b_keys, second.count, b_from, marks, sources);
      na = keep_marked(a_keys, first.count, a_to, marks, sources, ka);
      if (na == 0) return;
      if constexpr (kRa) turn(ka, na);
      // The targets kept; the second list's arcs out of them.
      const std::uint8_t targets = next_mark(js);
      for (std::uint32_t x = 0; x < na; ++x) marks[key_to(ka[x])] = targets;
      nb = keep_marked(b_keys, second.count, b_from, marks, targets, kb);
      if constexpr (kRb) turn(kb, nb);
    };
    using Yes = std::true_type;
    using No = std::false_type;
    if (first.reversed) {
      if (second.reversed)
        semi_join(Yes{}, Yes{});
      else
        semi_join(Yes{}, No{});
    } else {
      if (second.reversed)
        semi_join(No{}, Yes{});
      else
        semi_join(No{}, No{});
    }
    if (na == 0) continue;
    // The kept arcs chained by their shared vertex w, each keypoint pair
    // once (views store a pair once per view that describes it
    // differently): linear in the kept arcs, where sorting both lists
    // by w took a quarter of the completion. The triples come out in
    // another order; they are sorted below.
    std::uint32_t* const head = js.chain_head.data();
    std::uint32_t* const next_a = js.chain_next.data();
    std::uint32_t* const next_b = next_a + na;
    auto absent = [](const std::uint64_t* keys, const std::uint32_t* next, std::uint32_t entry,
                     std::uint64_t key) {
      for (std::uint32_t e = entry; e != 0; e = next[e - 1])
        if (keys[e - 1] == key) return false;
      return true;
    };
    for (std::uint32_t x = 0; x < nb; ++x) {
      std::uint32_t& first_b = head[2 * std::size_t{key_from(kb[x])} + 1];
      if (!absent(kb, next_b, first_b, kb[x])) continue;
      next_b[x] = first_b;
      first_b = x + 1;
    }
    std::uint32_t joined = 0;
    for (std::uint32_t y = 0; y < na; ++y) {
      const std::uint32_t w = key_to(ka[y]);
      std::uint32_t& first_a = head[2 * std::size_t{w}];
      if (!absent(ka, next_a, first_a, ka[y])) continue;
      if (first_a == 0) js.joined[joined++] = w;
      next_a[y] = first_a;
      first_a = y + 1;
    }
    // Candidates wait in a batch, so that their closing arcs' look-ups in
    // the model overlap their cache misses (ArcAdjacency::find).
    constexpr int kBatch = ArcAdjacency::kBatch;
    std::array<std::uint32_t, 3> batch[kBatch];
    std::uint32_t row[kBatch], target[kBatch];
    int pending = 0;
    auto flush = [&]() {
      const std::uint64_t* begin[kBatch];
      const std::uint64_t* end[kBatch];
      in.adjacency->find(row, target, pending, begin, end);
      for (int i = 0; i < pending; ++i)
        if (begin[i] != end[i]) in.search->prefetch(static_cast<std::uint32_t>(*begin[i]));
      for (int i = 0; i < pending && room; ++i) {
        bool similar = false;
        for (const std::uint64_t* e = begin[i]; e != end[i] && !similar; ++e)
          similar = in.search->matches(query, static_cast<std::uint32_t>(*e));
        if (!similar) continue;
        ++js.completion_closed;
        if (js.triple_count == capacity) {
          room = false;
          break;
        }
        js.triples[js.triple_count++] = batch[i];
      }
      pending = 0;
    };
    // Scene arc c -> a against model arcs t -> u (flipped: a -> c, u -> t).
    auto close = [&](std::uint32_t u, std::uint32_t w, std::uint32_t t) {
      if (t == u) return;
      ++js.completion_tried;
      std::array<std::uint32_t, 3> v;
      v[p] = u;
      v[(p + 1) % 3] = w;
      v[(p + 2) % 3] = t;
      if (!(orient(model_points[v[0]], model_points[v[1]], model_points[v[2]]) > 0.f)) return;
      ++js.completion_clockwise;
      if (!plausible(v.data())) return;
      ++js.completion_plausible;
      batch[pending] = v;
      row[pending] = flip ? u : t;
      target[pending] = flip ? t : u;
      if (++pending == kBatch) flush();
    };
    // The closing arc is looked up in the row of t (c_m), or of u (a_m)
    // when flipped: within a w, the outer loop runs over the arcs that fix
    // that row, so its look-ups after the first hit the cache.
    for (std::uint32_t j = 0; j < joined && room; ++j) {
      const std::uint32_t w = js.joined[j];
      const std::uint32_t first_a = head[2 * std::size_t{w}];
      const std::uint32_t first_b = head[2 * std::size_t{w} + 1];
      if (flip) {
        for (std::uint32_t ea = first_a; ea != 0 && room; ea = next_a[ea - 1])
          for (std::uint32_t eb = first_b; eb != 0 && room; eb = next_b[eb - 1])
            close(key_from(ka[ea - 1]), w, key_to(kb[eb - 1]));
      } else {
        for (std::uint32_t eb = first_b; eb != 0 && room; eb = next_b[eb - 1])
          for (std::uint32_t ea = first_a; ea != 0 && room; ea = next_a[ea - 1])
            close(key_from(ka[ea - 1]), w, key_to(kb[eb - 1]));
      }
    }
    for (std::uint32_t j = 0; j < joined; ++j) head[2 * std::size_t{js.joined[j]}] = 0;
    for (std::uint32_t x = 0; x < nb; ++x) head[2 * std::size_t{key_from(kb[x])} + 1] = 0;
    if (pending > 0 && room) flush();
  }
  // A circuit all three lists hold is found by every pass.
  std::sort(js.triples.begin(), js.triples.begin() + js.triple_count);
  js.triple_count = static_cast<std::uint32_t>(
      std::unique(js.triples.begin(), js.triples.begin() + js.triple_count) - js.triples.begin());
  return room;
}

template <class Lists>
bool Selector::join(const SelectionInput& in, const Limits& limits, const SceneKeygraph* first,
                    const SceneKeygraph* last, JoinScratch& js, WorkVector<KeygraphMatch>& out,
                    Lists&& list_for) {
  const auto per_query = static_cast<std::size_t>(std::max(0, limits.max_arc_matches));
  const bool completion =
      in.adjacency != nullptr && in.params->graph.structure == Structure::kCircuit3;
  const Structure structure = in.params->graph.structure;
  const int k = vertex_count(structure);
  // An arc keygraph has one arc; a circuit has as many arcs as vertices.
  const int looked_up_arcs = structure == Structure::kArc ? 1 : k;
  const Point2f* model_points = in.index->keypoints();
  const WorkVector<int>& tri = in.triangulation->triangles();
  const auto cap = static_cast<std::size_t>(limits.max_correspondences);

  const Params& params = *in.params;
  const bool check_vertices = in.model_descriptors != nullptr && in.scene_descriptors != nullptr;
  const float vertex_max2 = params.descriptor.vertex_threshold * params.descriptor.vertex_threshold;
  constexpr auto kRow = static_cast<std::size_t>(kVertexDescriptorSize);
  auto similar_vertices = [&](const std::uint32_t* model, const SceneKeygraph& g) {
    for (int i = 0; i < k; ++i) {
      const auto v = static_cast<std::size_t>(tri[g.edges[i]]);
      if (vertex_distance2(in.model_descriptors + model[i] * kRow, in.model_inverse_norms[model[i]],
                           in.scene_descriptors + v * kRow,
                           in.scene_inverse_norms[v]) > vertex_max2)
        return false;
    }
    return true;
  };
  // A keygraph's model and that model's smallest local area scale, by its
  // first model keypoint.
  struct Owner {
    int model;
    float min_area;
  };
  const std::uint16_t* owners = owners_.empty() ? nullptr : owners_.data();
  auto owner_of = [&](std::uint32_t keypoint) {
    const int model = owners != nullptr ? owners[keypoint] : in.index->model_of_keypoint(keypoint);
    return Owner{model, min_areas_[static_cast<std::size_t>(model)]};
  };
  auto plausible = [&](const std::uint32_t* model, const SceneKeygraph& g) {
    Point2f mp[kMaxVertices], sp[kMaxVertices];
    for (int i = 0; i < k; ++i) {
      mp[i] = model_points[model[i]];
      sp[i] = in.scene_points[tri[g.edges[i]]];
    }
    return plausible_local_map(mp, sp, k, params, owner_of(model[0]).min_area);
  };
  // Appends a plausible correspondence (`checked`: already known to be);
  // false when the output is full.
  auto emit = [&](const std::uint32_t* model, const SceneKeygraph& g, bool checked = false) {
    if (!checked && !plausible(model, g)) return true;
    const int model_id = owner_of(model[0]).model;
    if (in.model_searched != nullptr && in.model_searched[model_id] == 0) return true;
    if (check_vertices && !similar_vertices(model, g)) {
      ++js.vertex_rejections;
      return true;
    }
    if (out.size() >= cap) return false;
    KeygraphMatch m;
    m.model_id = model_id;
    for (int i = 0; i < k; ++i) {
      m.model_vertices[i] = model[i];
      m.scene_vertices[i] = tri[g.edges[i]];
    }
    out.push_back(m);
    return true;
  };

  for (const SceneKeygraph* gi = first; gi != last; ++gi) {
    // The time budget, every 32 keygraphs.
    if (in.deadline != nullptr && ((gi - first) & 31) == 31 &&
        std::chrono::steady_clock::now() > *in.deadline) {
      out_of_time_.store(true, std::memory_order_relaxed);
      return true;
    }
    const SceneKeygraph& g = *gi;
    ArcList lists[kMaxVertices];
    bool room = true;
    if (completion) {
      // Every arc is looked up (the closing arc needs its query); two lists
      // can make a circuit.
      int found = 0;
      for (int i = 0; i < 3; ++i) {
        lists[i] = list_for(g.edges[i]);
        found += lists[i].count > 0 ? 1 : 0;
      }
      if (found < 2) continue;
      const bool all =
          complete_circuit(in, g, lists, static_cast<std::uint32_t>(3 * per_query), js,
                           [&](const std::uint32_t* model) { return plausible(model, g); });
      if (!all) js.truncated_completion = true;
      for (std::uint32_t x = 0; x < js.triple_count && room; ++x)
        room = emit(js.triples[x].data(), g, true);
      if (!room) return false;
      continue;
    }
    bool empty = false;
    for (int i = 0; i < looked_up_arcs && !empty; ++i) {
      lists[i] = list_for(g.edges[i]);
      empty = lists[i].count == 0;
    }
    if (empty) continue;
    if (k == 2) {
      // Each keypoint pair once (views may store it several times).
      std::uint64_t* keys = js.kept[0].data();
      const std::uint32_t count = std::min(lists[0].count, static_cast<std::uint32_t>(per_query));
      std::copy_n(pool_.data() + lists[0].begin, count, keys);
      sort_arc_keys(keys, js.sort_scratch.data(), count, id_bits_);
      const auto unique = static_cast<std::uint32_t>(std::unique(keys, keys + count) - keys);
      for (std::uint32_t x = 0; x < unique && room; ++x) {
        const std::uint64_t key = keys[x];
        std::uint32_t v[kMaxVertices] = {key_from(key), key_to(key), 0, 0};
        if (lists[0].reversed) std::swap(v[0], v[1]);
        room = emit(v, g);
      }
      if (!room) return false;
      continue;
    }
    // Only the few arcs whose ends are candidates of both their vertices
    // can close a circuit: join those, sorted by (from, to).
    const bool joinable = candidate_lists(lists, k, js);
    if (!joinable) continue;
    const std::uint64_t* r[kMaxVertices] = {js.kept[0].data(), js.kept[1].data(), js.kept[2].data(),
                                            js.kept[3].data()};
    const std::uint32_t* n = js.kept_count;
    for (std::uint32_t i0 = 0; i0 < n[0] && room; ++i0) {
      std::uint32_t v[kMaxVertices] = {key_from(r[0][i0]), key_to(r[0][i0]), 0, 0};
      // Join (a_m, b_m) with the similar arcs leaving b_m.
      const std::uint64_t *b_lo, *b_hi;
      keys_from(r[1], n[1], v[1], b_lo, b_hi);
      for (const std::uint64_t* p1 = b_lo; p1 != b_hi && room; ++p1) {
        v[2] = key_to(*p1);
        if (v[2] == v[0]) continue;
        if (k == 3) {
          // (c_m, a_m) must be similar to (c_s, a_s), and the triple clockwise.
          if (!contains_key(r[2], n[2], arc_key(v[2], v[0]))) continue;
          if (!(orient(model_points[v[0]], model_points[v[1]], model_points[v[2]]) > 0.f)) continue;
          room = emit(v, g);
          continue;
        }
        const std::uint64_t *c_lo, *c_hi;
        keys_from(r[2], n[2], v[2], c_lo, c_hi);
        for (const std::uint64_t* p2 = c_lo; p2 != c_hi && room; ++p2) {
          v[3] = key_to(*p2);
          if (v[3] == v[0] || v[3] == v[1]) continue;
          if (!contains_key(r[3], n[3], arc_key(v[3], v[0]))) continue;
          const Point2f q[4] = {model_points[v[0]], model_points[v[1]], model_points[v[2]],
                                model_points[v[3]]};
          if (!is_clockwise_circuit(q, 4)) continue;
          room = emit(v, g);
        }
      }
    }
    if (!room) return false;
  }
  return true;
}

void Selector::select(const SelectionInput& in, const Limits& limits,
                      WorkVector<KeygraphMatch>& matches, DetectStats& stats) {
  matches.clear();
  out_of_time_.store(false, std::memory_order_relaxed);
  const std::size_t edges = in.triangulation->triangles().size();
  state_.assign(edges, kUnseen);
  begin_.resize(edges);
  count_.resize(edges);
  pool_used_ = 0;
  id_bits_ = id_bits(in.index->keypoint_count());
  // Half the smallest pose area scale of each model (homography.h): a local
  // map may shrink twice as much as the whole pose. Within reserve()'s
  // capacity: no allocation.
  const Params& params = *in.params;
  min_areas_.resize(static_cast<std::size_t>(in.index->model_count()));
  for (int m = 0; m < in.index->model_count(); ++m) {
    const ModelInfo info = in.index->model(m);
    min_areas_[static_cast<std::size_t>(m)] =
        params.views.min_size > 0.f
            ? static_cast<float>(0.5 * smallest_area_scale(params, info.width, info.height))
            : 0.5f / static_cast<float>(params.ransac.max_scale_change);
  }
  const bool completion =
      in.adjacency != nullptr && in.params->graph.structure == Structure::kCircuit3;
  const SceneKeygraph* keygraphs = in.keygraphs->data();
  const SceneKeygraph* keygraphs_end = keygraphs + in.keygraphs->size();
  const int threads = completion && in.workers != nullptr
                          ? std::min(in.workers->threads(), static_cast<int>(scratch_.size()))
                          : 1;
  for (int t = 0; t < threads; ++t)
    prepare(scratch_[static_cast<std::size_t>(t)], in, limits, completion);
  bool full = false;
  if (!completion) {
    // Look-ups on demand, in keygraph order: one thread.
    JoinScratch& s = scratch_[0];
    full = !join(in, limits, keygraphs, keygraphs_end, s, matches,
                 [&](int e) { return lookup(in, e, limits, stats, s); });
  } else {
    total_.resize(edges);
    search_chosen(in, limits, stats);
    auto listed = [&](int e) { return list_of(in, e); };
    if (threads == 1) {
      full = !join(in, limits, keygraphs, keygraphs_end, scratch_[0], matches, listed);
      chunks_.clear();
    } else {
      // Runs of keygraphs, each joined by whichever thread takes it into
      // that thread's output; then concatenated in keygraph order up to
      // max_correspondences: what one thread would have selected. A thread
      // whose output filled holds, in order, every correspondence of its
      // runs that the cut can need (the runs before hold at least as many).
      const auto count = static_cast<std::size_t>(keygraphs_end - keygraphs);
      const std::size_t runs =
          std::min(count, static_cast<std::size_t>(threads) * kChunksPerThread);
      chunks_.assign(runs, Chunk{});
      auto join_run = [&](int run, int worker) {
        JoinScratch& s = scratch_[static_cast<std::size_t>(worker)];
        Chunk& c = chunks_[static_cast<std::size_t>(run)];
        c.worker = worker;
        c.begin = static_cast<std::uint32_t>(s.out.size());
        s.truncated_completion = false;
        const std::size_t from = count * static_cast<std::size_t>(run) / runs;
        const std::size_t to = count * static_cast<std::size_t>(run + 1) / runs;
        c.full = !join(in, limits, keygraphs + from, keygraphs + to, s, s.out, listed);
        c.end = static_cast<std::uint32_t>(s.out.size());
        c.truncated_completion = s.truncated_completion;
      };
      in.workers->run(static_cast<int>(runs), join_run);
      // One thread would have stopped at the first correspondence past the
      // cap: there is one when a run filled its thread's output, or when
      // the runs hold more than the cap together.
      const auto cap = static_cast<std::size_t>(limits.max_correspondences);
      std::size_t available = 0;
      for (const Chunk& c : chunks_) {
        if (matches.size() < cap && c.truncated_completion) stats.truncated_correspondences = true;
        const WorkVector<KeygraphMatch>& from = scratch_[static_cast<std::size_t>(c.worker)].out;
        for (std::uint32_t i = c.begin; i < c.end && matches.size() < cap; ++i)
          matches.push_back(from[i]);
        available += c.end - c.begin;
        full = full || c.full;
        if (c.full) break;
      }
      full = full || available > cap;
    }
  }
  if (full) stats.truncated_correspondences = true;
  stats.correspondences = static_cast<int>(matches.size());
  // The counts of this select() (with scene_upsample 3, the last pass's).
  long long tried = 0, clockwise = 0, plausible = 0, closed = 0, in_join = 0, kept = 0;
  for (int t = 0; t < threads; ++t) {
    const JoinScratch& js = scratch_[static_cast<std::size_t>(t)];
    tried += static_cast<long long>(js.completion_tried);
    clockwise += static_cast<long long>(js.completion_clockwise);
    plausible += static_cast<long long>(js.completion_plausible);
    closed += static_cast<long long>(js.completion_closed);
    in_join += static_cast<long long>(js.semi_join_in);
    kept += static_cast<long long>(js.semi_join_kept);
    stats.vertex_rejections += static_cast<long long>(js.vertex_rejections);
    if (threads == 1 && js.truncated_completion) stats.truncated_correspondences = true;
  }
  stats.completion_tried = tried;
  stats.completion_clockwise = clockwise;
  stats.completion_plausible = plausible;
  stats.completion_closed = closed;
  stats.join_arcs_in = in_join;
  stats.join_arcs_kept = kept;
}

bool Selector::join_state_clear() const {
  for (const JoinScratch& s : scratch_) {
    for (std::uint8_t f : s.flags)
      if (f != 0) return false;
    for (std::uint32_t h : s.chain_head)
      if (h != 0) return false;
  }
  return true;
}

}  // namespace kg
