// The scene's arc descriptors (paper section 6, scene side; step 7 of the
// frame in docs/ARCHITECTURE.md): the frame blurred once, then every arc
// of the frame's keygraphs described and turned into a query of the index's
// search (quantised to the index's encoding, with the arc's scale
// attributes, core/description/arc_attributes.h).
//
// Arcs are Delaunay half-edges. Of the two directions of an edge only one
// is described: the one the keygraphs reach first (keygraph order, then
// edge order within a keygraph), which is the one the selection looks up
// first; the selection reads the other direction's similar model arcs
// reversed (core/selection/selection.h). Without circuit completion the
// selection stops at a keygraph's first empty arc list and may then reach
// an edge from its other side first: it asks describe_now() for that
// direction, as the selection always did, so every configuration selects
// the correspondences it selected when arcs were described on demand.
#pragma once

#include <cstdint>

#include "core/description/arc_types.h"
#include "core/image/plane.h"
#include "core/index/arc_search.h"
#include "core/keygraphs/delaunay.h"
#include "core/keygraphs/keygraph.h"
#include "core/support/workspace.h"
#include "keygraph/image.h"
#include "keygraph/params.h"

namespace kg {

class SceneArcs {
 public:
  explicit SceneArcs(std::pmr::memory_resource* memory = std::pmr::get_default_resource());

  // Sizes the buffers for frames up to max_width x max_height blurred with
  // `blur_sigma` and triangulations of up to max_points keypoints:
  // blur() and describe() then allocate nothing.
  void reserve(int max_width, int max_height, int max_points, float blur_sigma);

  // The frame blurred by params.blur_sigma (the profiles' image; also the
  // triangle check's and the pose's).
  void blur(ImageView frame, const DescriptorParams& params);
  ImageView blurred() const { return view_of(blurred_); }

  // Describes the first `arcs_per_keygraph` arcs of each keygraph (all of a
  // circuit's; the one arc of an arc keygraph), each edge once, on the
  // blurred frame. points and scales (detector sigma, nullptr: unknown) are
  // the sampled scene keypoints the triangulation joins; they, the
  // triangulation and `search` must outlive the next describe().
  void describe(const ArcSearch& search, const Params& params, const Point2f* points,
                const float* scales, const Delaunay& triangulation,
                const WorkVector<SceneKeygraph>& keygraphs, int arcs_per_keygraph);

  // Whether describe() chose half-edge e for its edge (rather than its
  // opposite); valid for the arcs of the keygraphs described.
  bool chosen(int e) const { return chosen_[static_cast<std::size_t>(e)] != 0; }
  // Whether half-edge e has a descriptor (and so a query): chosen or
  // described_now(), longer than graph.min_distance and inside the frame
  // with a profile that is not flat.
  bool described(int e) const { return described_[static_cast<std::size_t>(e)] != 0; }
  const ArcSearch::Query& query(int e) const { return queries_[static_cast<std::size_t>(e)]; }
  // Describes half-edge e although its opposite was chosen (see above).
  void describe_now(int e);

  // Arcs with a descriptor since describe() (DetectStats::arcs_described).
  int described_count() const { return described_count_; }

 private:
  // Describes half-edge e and stores its query; false when it has none.
  bool describe_edge(int e);

  Plane<std::uint8_t> blurred_;
  Plane<float> blur_scratch_;
  WorkVector<std::uint8_t> chosen_;
  WorkVector<std::uint8_t> described_;
  WorkVector<ArcSearch::Query> queries_;
  WorkVector<float> profile_;
  WorkVector<std::int32_t> sums_;  // fixed-point profiles
  int described_count_ = 0;
  // describe()'s inputs, for describe_now().
  const ArcSearch* search_ = nullptr;
  const Params* params_ = nullptr;
  const Point2f* points_ = nullptr;
  const float* scales_ = nullptr;
  const Delaunay* triangulation_ = nullptr;
};

}  // namespace kg
