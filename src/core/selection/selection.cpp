#include "core/selection/selection.h"

#include <algorithm>
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

}  // namespace

Selector::ArcList Selector::lookup(const SelectionInput& in, int e, const Limits& limits,
                                   DetectStats& stats) {
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
  const ArcSearch::Query& query = arcs.query(e);
  const auto cap = static_cast<std::uint32_t>(limits.max_arc_matches);
  found_.resize(cap);
  const std::uint32_t total = in.search->search(query, found_.data(), cap);
  stats.arc_matches += total;
  std::uint32_t n = std::min(total, cap);
  const std::size_t room = pool_limit_ - std::min(pool_limit_, pool_used_);
  if (n > room) n = static_cast<std::uint32_t>(room);
  if (n < total) stats.truncated_arc_matches = true;
  // Within the reserved pool (room), so the resize never allocates.
  if (pool_.size() < pool_used_ + n) pool_.resize(pool_used_ + n);
  pool_used_ += n;
  std::uint64_t* keys = pool_.data() + begin_[e];
  const std::uint32_t* slots = found_.data();
  for (std::uint32_t i = 0; i < n; ++i) IndexInternals::prefetch_arc(*in.index, slots[i]);
  for (std::uint32_t i = 0; i < n; ++i) {
    const ModelArc arc = in.index->arc(slots[i]);
    keys[i] = arc_key(arc.from, arc.to);
  }
  count_[e] = n;
  return {begin_[e], n, false};
}

bool Selector::candidate_lists(const ArcList* lists, int k) {
  // A semi-join: list i is cut to the arcs u -> v where u is the target of
  // an arc kept in list i - 1 (of the whole last list, for list 0) and v
  // the source of one in list i + 1 (whole; of kept list 0, for the last).
  // Flags per model keypoint say which lists it leaves (bit i) and enters
  // (bit 4 + i); each pass clears what it no longer needs, so the flags are
  // all clear again on return.
  std::uint8_t* const flags = flags_.data();
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
    semi_join_in_ += count[i];
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
    std::uint64_t* const out = kept_[i].data();
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
    kept_count_[i] = n;
    semi_join_kept_ += n;
    if (n == 0) {
      // No circuit: clear the later lists' bits and the kept lists' marks.
      for (int j = i + 1; j <= last; ++j) clear(keys[j], count[j]);
      for (int j = 0; j < i; ++j) clear(kept_[j].data(), kept_count_[j]);
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
  for (int j = 0; j < last; ++j) clear(kept_[j].data(), kept_count_[j]);
  for (int i = 0; i <= last; ++i) {
    sort_arc_keys(kept_[i].data(), sort_scratch_.data(), kept_count_[i], id_bits_);
    // Views store one keypoint pair once per view that describes it
    // differently; a pair found twice would select its circuits twice.
    std::uint64_t* sorted = kept_[i].data();
    kept_count_[i] =
        static_cast<std::uint32_t>(std::unique(sorted, sorted + kept_count_[i]) - sorted);
  }
  return true;
}

template <class Plausible>
bool Selector::complete_circuit(const SelectionInput& in, const SceneKeygraph& g,
                                const ArcList* lists, std::uint32_t capacity,
                                Plausible&& plausible) {
  // Each pair of consecutive lists (a -> b, b -> c) is joined on b by a
  // semi-join (flag bit 0: sources of the second list, bit 1: targets kept
  // of the first), as candidate_lists() does for all three; the closing arc
  // c -> a is then looked up in the model and compared with the scene arc.
  std::uint8_t* const flags = flags_.data();
  const Point2f* model_points = in.index->keypoints();
  const int* opposite = in.triangulation->halfedges().data();
  auto arc = [](std::uint64_t key, int s) { return (key >> s) | (key << ((64 - s) & 63)); };
  triple_count_ = 0;
  bool room = true;
  for (int p = 0; p < 3 && room; ++p) {
    const ArcList& first = lists[p];
    const ArcList& second = lists[(p + 1) % 3];
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
    const int sa = first.reversed ? 32 : 0, sb = second.reversed ? 32 : 0;
    for (std::uint32_t x = 0; x < second.count; ++x) flags[key_from(arc(b_keys[x], sb))] |= 1;
    std::uint64_t* const ka = kept_[0].data();
    std::uint32_t na = 0;
    for (std::uint32_t x = 0; x < first.count; ++x) {
      const std::uint64_t a = arc(a_keys[x], sa);
      ka[na] = a;
      na += static_cast<std::uint32_t>((flags[key_to(a)] & 1) != 0);
    }
    for (std::uint32_t x = 0; x < second.count; ++x) flags[key_from(arc(b_keys[x], sb))] = 0;
    if (na == 0) continue;
    for (std::uint32_t x = 0; x < na; ++x) flags[key_to(ka[x])] |= 2;
    std::uint64_t* const kb = kept_[1].data();
    std::uint32_t nb = 0;
    for (std::uint32_t x = 0; x < second.count; ++x) {
      const std::uint64_t b = arc(b_keys[x], sb);
      kb[nb] = b;
      nb += static_cast<std::uint32_t>((flags[key_from(b)] & 2) != 0);
    }
    for (std::uint32_t x = 0; x < na; ++x) flags[key_to(ka[x])] = 0;
    // The kept arcs chained by their shared vertex w, each keypoint pair
    // once (views store a pair once per view that describes it
    // differently): linear in the kept arcs, where sorting both lists
    // by w took a quarter of the completion. The triples come out in
    // another order; they are sorted below.
    std::uint32_t* const head = chain_head_.data();
    std::uint32_t* const next_a = chain_next_.data();
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
      if (first_a == 0) joined_[joined++] = w;
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
        ++completion_closed_;
        if (triple_count_ == capacity) {
          room = false;
          break;
        }
        triples_[triple_count_++] = batch[i];
      }
      pending = 0;
    };
    // Scene arc c -> a against model arcs t -> u (flipped: a -> c, u -> t).
    auto close = [&](std::uint32_t u, std::uint32_t w, std::uint32_t t) {
      if (t == u) return;
      ++completion_tried_;
      std::array<std::uint32_t, 3> v;
      v[p] = u;
      v[(p + 1) % 3] = w;
      v[(p + 2) % 3] = t;
      if (!(orient(model_points[v[0]], model_points[v[1]], model_points[v[2]]) > 0.f)) return;
      ++completion_clockwise_;
      if (!plausible(v.data())) return;
      ++completion_plausible_;
      batch[pending] = v;
      row[pending] = flip ? u : t;
      target[pending] = flip ? t : u;
      if (++pending == kBatch) flush();
    };
    // The closing arc is looked up in the row of t (c_m), or of u (a_m)
    // when flipped: within a w, the outer loop runs over the arcs that fix
    // that row, so its look-ups after the first hit the cache.
    for (std::uint32_t j = 0; j < joined && room; ++j) {
      const std::uint32_t w = joined_[j];
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
    for (std::uint32_t j = 0; j < joined; ++j) head[2 * std::size_t{joined_[j]}] = 0;
    for (std::uint32_t x = 0; x < nb; ++x) head[2 * std::size_t{key_from(kb[x])} + 1] = 0;
    if (pending > 0 && room) flush();
  }
  // A circuit all three lists hold is found by every pass.
  std::sort(triples_.begin(), triples_.begin() + triple_count_);
  triple_count_ = static_cast<std::uint32_t>(
      std::unique(triples_.begin(), triples_.begin() + triple_count_) - triples_.begin());
  return room;
}

void Selector::reserve(const Limits& limits, std::uint32_t model_keypoints, bool completion) {
  const auto half_edges = 6 * static_cast<std::size_t>(std::max(0, limits.max_scene_keypoints));
  state_.reserve(half_edges);
  begin_.reserve(half_edges);
  count_.reserve(half_edges);
  pool_limit_ = static_cast<std::size_t>(std::max(0, limits.max_arc_pool));
  pool_.reserve(pool_limit_);
  found_.reserve(static_cast<std::size_t>(std::max(0, limits.max_arc_matches)));
  const auto per_query = static_cast<std::size_t>(std::max(0, limits.max_arc_matches));
  sort_scratch_.reserve(per_query);
  for (WorkVector<std::uint64_t>& kept : kept_) kept.reserve(per_query);
  flags_.reserve(model_keypoints);
  if (completion) {
    triples_.reserve(3 * per_query);  // a circuit is found by up to 3 passes before dedupe
    chain_head_.reserve(2 * static_cast<std::size_t>(model_keypoints));
    chain_next_.reserve(2 * per_query);
    joined_.reserve(per_query);
  }
}

void Selector::select(const SelectionInput& in, const Limits& limits,
                      WorkVector<KeygraphMatch>& matches, DetectStats& stats) {
  matches.clear();
  const std::size_t edges = in.triangulation->triangles().size();
  state_.assign(edges, kUnseen);
  begin_.resize(edges);
  count_.resize(edges);
  pool_used_ = 0;
  id_bits_ = id_bits(in.index->keypoint_count());
  // Within what reserve() sized (the Detector's limits and index), this
  // never allocates.
  const auto per_query = static_cast<std::size_t>(std::max(0, limits.max_arc_matches));
  if (sort_scratch_.size() < per_query) sort_scratch_.resize(per_query);
  for (WorkVector<std::uint64_t>& kept : kept_)
    if (kept.size() < per_query) kept.resize(per_query);
  // All clear between keygraphs (candidate_lists() clears what it flags).
  flags_.assign(in.index->keypoint_count(), 0);
  const bool completion =
      in.adjacency != nullptr && in.params->graph.structure == Structure::kCircuit3;
  if (in.adjacency != nullptr) {
    if (triples_.size() < 3 * per_query) triples_.resize(3 * per_query);
    if (chain_next_.size() < 2 * per_query) chain_next_.resize(2 * per_query);
    if (joined_.size() < per_query) joined_.resize(per_query);
    // All zero between passes: set once per index size.
    const std::size_t heads = 2 * static_cast<std::size_t>(in.index->keypoint_count());
    if (chain_head_.size() != heads) chain_head_.assign(heads, 0);
  }
  semi_join_in_ = 0;
  semi_join_kept_ = 0;
  completion_tried_ = completion_clockwise_ = 0;
  completion_plausible_ = completion_closed_ = 0;
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
      const auto s = static_cast<std::size_t>(tri[g.edges[i]]);
      if (vertex_distance2(in.model_descriptors + model[i] * kRow, in.model_inverse_norms[model[i]],
                           in.scene_descriptors + s * kRow,
                           in.scene_inverse_norms[s]) > vertex_max2)
        return false;
    }
    return true;
  };
  // Half the smallest pose area scale of each model (homography.h): a local
  // map may shrink twice as much as the whole pose.
  const float symmetric_min_area = 0.5f / static_cast<float>(params.ransac.max_scale_change);
  // The model of the last keypoint asked about, with its keypoint range and
  // smallest local area: a keygraph's candidates mostly lie in one model,
  // and decoding its record for each of them was a tenth of the completion.
  struct Owner {
    int model = -1;
    float min_area = 0.f;
  };
  Owner last;
  std::uint32_t last_begin = 0, last_count = 0;
  auto owner_of = [&](std::uint32_t keypoint) {
    if (keypoint - last_begin < last_count) return last;
    last.model = in.index->model_of_keypoint(keypoint);
    const ModelInfo info = in.index->model(last.model);
    last_begin = info.keypoint_begin;
    last_count = info.keypoint_count;
    last.min_area =
        params.views.min_size > 0.f
            ? static_cast<float>(0.5 * smallest_area_scale(params, info.width, info.height))
            : symmetric_min_area;
    return last;
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
      ++stats.vertex_rejections;
      return true;
    }
    if (matches.size() >= cap) {
      stats.truncated_correspondences = true;
      return false;
    }
    KeygraphMatch m;
    m.model_id = model_id;
    for (int i = 0; i < k; ++i) {
      m.model_vertices[i] = model[i];
      m.scene_vertices[i] = tri[g.edges[i]];
    }
    matches.push_back(m);
    return true;
  };

  for (const SceneKeygraph& g : *in.keygraphs) {
    ArcList lists[kMaxVertices];
    bool room = true;
    if (completion) {
      // Every arc is looked up (the closing arc needs its query); two lists
      // can make a circuit.
      int found = 0;
      for (int i = 0; i < 3; ++i) {
        lists[i] = lookup(in, g.edges[i], limits, stats);
        found += lists[i].count > 0 ? 1 : 0;
      }
      if (found < 2) continue;
      const bool all =
          complete_circuit(in, g, lists, static_cast<std::uint32_t>(3 * per_query),
                           [&](const std::uint32_t* model) { return plausible(model, g); });
      if (!all) stats.truncated_correspondences = true;
      for (std::uint32_t x = 0; x < triple_count_ && room; ++x)
        room = emit(triples_[x].data(), g, true);
      if (!room) break;
      continue;
    }
    bool empty = false;
    for (int i = 0; i < looked_up_arcs && !empty; ++i) {
      lists[i] = lookup(in, g.edges[i], limits, stats);
      empty = lists[i].count == 0;
    }
    if (empty) continue;
    if (k == 2) {
      // Each keypoint pair once (views may store it several times).
      std::uint64_t* keys = kept_[0].data();
      const std::uint32_t count = std::min(lists[0].count, static_cast<std::uint32_t>(per_query));
      std::copy_n(pool_.data() + lists[0].begin, count, keys);
      sort_arc_keys(keys, sort_scratch_.data(), count, id_bits_);
      const auto unique = static_cast<std::uint32_t>(std::unique(keys, keys + count) - keys);
      for (std::uint32_t x = 0; x < unique && room; ++x) {
        const std::uint64_t key = keys[x];
        std::uint32_t v[kMaxVertices] = {key_from(key), key_to(key), 0, 0};
        if (lists[0].reversed) std::swap(v[0], v[1]);
        room = emit(v, g);
      }
      if (!room) break;
      continue;
    }
    // Only the few arcs whose ends are candidates of both their vertices
    // can close a circuit: join those, sorted by (from, to).
    const bool joinable = candidate_lists(lists, k);
    if (!joinable) continue;
    const std::uint64_t* r[kMaxVertices] = {kept_[0].data(), kept_[1].data(), kept_[2].data(),
                                            kept_[3].data()};
    const std::uint32_t* n = kept_count_;
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
    if (!room) break;
  }
  stats.correspondences = static_cast<int>(matches.size());
  stats.completion_tried = static_cast<long long>(completion_tried_);
  stats.completion_clockwise = static_cast<long long>(completion_clockwise_);
  stats.completion_plausible = static_cast<long long>(completion_plausible_);
  stats.completion_closed = static_cast<long long>(completion_closed_);
  stats.join_arcs_in = static_cast<long long>(semi_join_in_);
  stats.join_arcs_kept = static_cast<long long>(semi_join_kept_);
}

}  // namespace kg
