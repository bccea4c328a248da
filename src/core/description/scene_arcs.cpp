#include "core/description/scene_arcs.h"

#include <algorithm>

#include "core/description/arc_attributes.h"
#include "core/description/arc_descriptor.h"
#include "core/description/descriptor_encoding.h"
#include "core/image/blur.h"
#include "core/sampling/sampling.h"

namespace kg {

SceneArcs::SceneArcs(std::pmr::memory_resource* memory)
    : blurred_(memory),
      blur_scratch_(memory),
      chosen_(memory),
      described_(memory),
      queries_(memory),
      profile_(memory),
      sums_(memory) {}

void SceneArcs::reserve(int max_width, int max_height, int max_points, float blur_sigma) {
  blurred_.reserve(max_width, max_height);
  blur_scratch_.reserve(max_width + 2 * blur_radius(blur_sigma), 2);
  // A triangulation of n points has fewer than 6n half-edges.
  const auto half_edges = 6 * static_cast<std::size_t>(std::max(0, max_points));
  chosen_.reserve(half_edges);
  described_.reserve(half_edges);
  queries_.reserve(half_edges);
  // A profile has at most the frame's longer side plus one samples.
  profile_.reserve(static_cast<std::size_t>(std::max(max_width, max_height)) + 1);
  sums_.reserve(profile_.capacity() + 30);
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
  const int* opposite = triangulation.halfedges().data();
  for (const SceneKeygraph& g : keygraphs) {
    for (int i = 0; i < arcs_per_keygraph; ++i) {
      const int e = g.edges[i];
      if (chosen_[static_cast<std::size_t>(e)] != 0) continue;
      const int o = opposite[e];
      if (o >= 0 && chosen_[static_cast<std::size_t>(o)] != 0) continue;
      chosen_[static_cast<std::size_t>(e)] = 1;
      describe_edge(e);
    }
  }
}

void SceneArcs::describe_now(int e) {
  if (described_[static_cast<std::size_t>(e)] == 0) describe_edge(e);
}

bool SceneArcs::describe_edge(int e) {
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
  if (fixed ? !arc_descriptor_fixed(image, a, b, dp, encoding_scale(dp.encoding), sums_, q)
            : !arc_descriptor(image, a, b, dp, profile_, d))
    return false;
  float attributes[kArcAttributes];
  const bool scaled =
      scales_ != nullptr && arc_attributes(a, b, scales_[from], scales_[to], attributes);
  queries_[static_cast<std::size_t>(e)] =
      fixed ? search_->query_quantised(q, scaled ? attributes : nullptr)
            : search_->query(d, scaled ? attributes : nullptr);
  described_[static_cast<std::size_t>(e)] = 1;
  ++described_count_;
  return true;
}

}  // namespace kg
