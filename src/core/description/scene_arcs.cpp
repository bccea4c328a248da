#include "core/description/scene_arcs.h"

#include <algorithm>

#include "core/description/arc_attributes.h"
#include "core/description/arc_descriptor.h"
#include "core/description/descriptor_encoding.h"
#include "core/image/blur.h"
#include "core/sampling/sampling.h"

namespace kg {

SceneArcs::SceneArcs(std::pmr::memory_resource* memory)
    : memory_(memory),
      scratch_(memory),
      blurred_(memory),
      blur_scratch_(memory),
      chosen_(memory),
      order_(memory),
      described_(memory),
      queries_(memory) {}

void SceneArcs::reserve(int max_width, int max_height, int max_points, float blur_sigma,
                        int threads, bool fill) {
  blurred_.reserve(max_width, max_height);
  blur_scratch_.reserve(max_width + 2 * blur_radius(blur_sigma), 2);
  // A triangulation of n points has fewer than 6n half-edges.
  const auto half_edges = 6 * static_cast<std::size_t>(std::max(0, max_points));
  chosen_.reserve(half_edges);
  order_.reserve(half_edges);
  described_.reserve(half_edges);
  queries_.reserve(half_edges);
  scratch_.reserve(static_cast<std::size_t>(std::max(1, threads)));
  scratch_.clear();
  for (int t = 0; t < std::max(1, threads); ++t) {
    // The measuring pass (fill false) must not write into its placeholder
    // memory: a scratch on the stack stands in, its buffers counted.
    Scratch stand_in(memory_);
    Scratch& s = fill ? scratch_.emplace_back(memory_) : stand_in;
    // A profile has at most the frame's longer side plus one samples.
    s.profile.reserve(static_cast<std::size_t>(std::max(max_width, max_height)) + 1);
    s.sums.reserve(s.profile.capacity() + 30);
  }
}

void SceneArcs::blur(ImageView frame, const DescriptorParams& params) {
  gaussian_blur(frame, params.blur_sigma, blurred_, blur_scratch_);
}

void SceneArcs::describe(const ArcSearch& search, const Params& params, const Point2f* points,
                         const float* scales, const Delaunay& triangulation,
                         const WorkVector<SceneKeygraph>& keygraphs, int arcs_per_keygraph) {
  search_ = &search;
  params_ = &params;
  points_ = points;
  scales_ = scales;
  triangulation_ = &triangulation;
  described_count_ = 0;
  const std::size_t edges = triangulation.triangles().size();
  chosen_.assign(edges, 0);
  described_.assign(edges, 0);
  queries_.resize(edges);
  order_.clear();
  const int* opposite = triangulation.halfedges().data();
  for (const SceneKeygraph& g : keygraphs) {
    for (int i = 0; i < arcs_per_keygraph; ++i) {
      const int e = g.edges[i];
      if (chosen_[static_cast<std::size_t>(e)] != 0) continue;
      const int o = opposite[e];
      if (o >= 0 && chosen_[static_cast<std::size_t>(o)] != 0) continue;
      chosen_[static_cast<std::size_t>(e)] = 1;
      order_.push_back(e);
    }
  }
  // Each arc on its own: the threads share the work in blocks.
  constexpr int kBlock = 32;
  const int n = static_cast<int>(order_.size());
  const int blocks = (n + kBlock - 1) / kBlock;
  auto describe_block = [&](int block, int worker) {
    Scratch& scratch = scratch_[static_cast<std::size_t>(worker)];
    const int end = std::min(n, (block + 1) * kBlock);
    for (int i = block * kBlock; i < end; ++i)
      describe_edge(order_[static_cast<std::size_t>(i)], scratch);
  };
  if (workers_ != nullptr && workers_->threads() <= static_cast<int>(scratch_.size())) {
    workers_->run(blocks, describe_block);
  } else {
    for (int b = 0; b < blocks; ++b) describe_block(b, 0);
  }
  for (int e : order_) described_count_ += described_[static_cast<std::size_t>(e)];
}

void SceneArcs::describe_now(int e) {
  if (described_[static_cast<std::size_t>(e)] != 0) return;
  if (describe_edge(e, scratch_[0])) ++described_count_;
}

bool SceneArcs::describe_edge(int e, Scratch& scratch) {
  const WorkVector<int>& tri = triangulation_->triangles();
  const int from = tri[static_cast<std::size_t>(e)];
  const int to = tri[static_cast<std::size_t>(Delaunay::next(e))];
  const Point2f a = points_[from];
  const Point2f b = points_[to];
  const DescriptorParams& dp = params_->descriptor;
  if (chebyshev(a, b) < params_->graph.min_distance) return false;
  // Integer encodings describe in fixed point (already quantised); float32
  // is the float reference.
  const bool fixed = uses_fixed_point(dp);
  ArcDescriptor d;
  std::int32_t q[kDescriptorSize];
  const ImageView image = blurred();
  if (fixed ? !arc_descriptor_fixed(image, a, b, dp, encoding_scale(dp.encoding), scratch.sums, q)
            : !arc_descriptor(image, a, b, dp, scratch.profile, d))
    return false;
  float attributes[kArcAttributes];
  const bool scaled =
      scales_ != nullptr && arc_attributes(a, b, scales_[from], scales_[to], attributes);
  queries_[static_cast<std::size_t>(e)] =
      fixed ? search_->query_quantised(q, scaled ? attributes : nullptr)
            : search_->query(d, scaled ? attributes : nullptr);
  described_[static_cast<std::size_t>(e)] = 1;
  return true;
}

}  // namespace kg
