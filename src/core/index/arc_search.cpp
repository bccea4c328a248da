#include "core/index/arc_search.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include "core/description/arc_attributes.h"
#include "core/description/descriptor_encoding.h"
#include "core/index/index_internals.h"

namespace kg {

ArcSearch::ArcSearch(const ModelIndex& index)
    : ArcSearch(index, leaves_for(index.params().descriptor, index.model_count())) {}

int ArcSearch::leaves_for(const DescriptorParams& params, std::uint64_t models) {
  const int base = params.max_search_leaves;
  const auto reference = static_cast<std::uint64_t>(std::max(0, params.search_reference_models));
  if (base <= 0 || reference == 0 || models <= reference) return std::max(0, base);
  // Each model adds arcs near a query (alike signs most: one family's
  // arrows, fonts and pictograms); a budget grown with the square root of
  // the models keeps most of a sign's arcs within reach at a cost that
  // grows more slowly than the index (docs/RESULTS.md, "Index size and
  // recall"). The models, not the arcs: ten unrelated photos with 680 000
  // arcs lose nothing at 20 leaves, fifty signs with 842 000 lose a quarter.
  const double grown =
      base * std::sqrt(static_cast<double>(models) / static_cast<double>(reference));
  const double cap = std::min(static_cast<double>(base) * kMaxLeavesGrowth,
                              static_cast<double>(std::numeric_limits<int>::max()));
  return static_cast<int>(std::lround(std::min(grown, cap)));
}

ArcSearch::ArcSearch(const ModelIndex& index, int max_leaves) {
  const Params& params = index.params();
  encoding_ = params.descriptor.encoding;
  const float radius = params.descriptor.similarity_threshold;
  radius2_ = radius * radius;
  box_ = attribute_box(params.graph);
  max_leaves_ = max_leaves;
  keys_ = IndexInternals::arc_keys(index);
  const std::uint32_t n = index.arc_count();
  const int depth = index.tree_depth();
  switch (encoding_) {
    case DescriptorEncoding::kFloat32:
      points_f32_ = IndexInternals::tree_points_f32(index);
      f32_ = ArcTreeView(IndexInternals::tree_points_f32(index), nullptr, n,
                         IndexInternals::tree_nodes_f32(index), depth,
                         IndexInternals::leaf_bounds_f32(index));
      break;
    case DescriptorEncoding::kInt16:
      points_i16_ = IndexInternals::tree_points_i16(index);
      i16_ = ArcTreeView16(IndexInternals::tree_points_i16(index), nullptr, n,
                           IndexInternals::tree_nodes_int(index), depth,
                           IndexInternals::leaf_bounds_i16(index));
      if (!scaled_radius2(radius, encoding_, std::numeric_limits<ArcTreeView16::Dist>::max(),
                          radius2_scaled_))
        radius2_scaled_ = 0;  // unreachable: validate_params checked the scaled radius
      break;
    case DescriptorEncoding::kInt8:
      points_i8_ = IndexInternals::tree_points_i8(index);
      i8_ = ArcTreeView8(IndexInternals::tree_points_i8(index), nullptr, n,
                         IndexInternals::tree_nodes_int(index), depth,
                         IndexInternals::leaf_bounds_i8(index));
      if (!scaled_radius2(radius, encoding_, std::numeric_limits<ArcTreeView8::Dist>::max(),
                          radius2_scaled_))
        radius2_scaled_ = 0;
      break;
  }
}

std::uint32_t ArcSearch::radius_search(const ArcDescriptor& q, const float* attributes,
                                       std::uint32_t* out, std::uint32_t capacity) const {
  return search(query(q, attributes), out, capacity);
}

std::uint32_t ArcSearch::radius_search_quantised(const std::int32_t* q, const float* attributes,
                                                 std::uint32_t* out, std::uint32_t capacity) const {
  if (encoding_ == DescriptorEncoding::kFloat32) return 0;  // searched with float descriptors
  return search(query_quantised(q, attributes), out, capacity);
}

ArcSearch::Query ArcSearch::query(const ArcDescriptor& q, const float* attributes) const {
  const float none[kArcAttributes] = {0.f, 0.f};
  Query out;
  out.box = box_ > 0 && attributes != nullptr;
  const ArcSearchPoint p = search_point(q, attributes != nullptr ? attributes : none);
  auto widen = [&out](const auto& encoded_point) {
    for (int i = 0; i < kSearchDims; ++i) out.point[i] = static_cast<float>(encoded_point[i]);
  };
  switch (encoding_) {
    case DescriptorEncoding::kFloat32:
      out.point = p;
      break;
    case DescriptorEncoding::kInt16:
      widen(encode_point<std::int16_t>(p));
      break;
    case DescriptorEncoding::kInt8:
      widen(encode_point<std::int8_t>(p));
      break;
  }
  return out;
}

ArcSearch::Query ArcSearch::query_quantised(const std::int32_t* q, const float* attributes) const {
  Query out;
  out.box = box_ > 0 && attributes != nullptr;
  for (int i = 0; i < kDescriptorSize; ++i) out.point[i] = static_cast<float>(q[i]);
  for (int i = 0; i < kArcAttributes; ++i)
    out.point[kDescriptorSize + i] = attributes != nullptr ? attributes[i] : 0.f;
  return out;
}

template <class T>
std::array<T, kSearchDims> ArcSearch::encoded(const Query& q) const {
  std::array<T, kSearchDims> p{};
  for (int i = 0; i < kSearchDims; ++i) p[i] = static_cast<T>(q.point[i]);
  return p;
}

std::uint32_t ArcSearch::search(const Query& q, std::uint32_t* out, std::uint32_t capacity) const {
  switch (encoding_) {
    case DescriptorEncoding::kFloat32: {
      const float b = q.box ? static_cast<float>(box_) : std::numeric_limits<float>::max();
      return max_leaves_ > 0
                 ? f32_.radius_search_approximate(q.point, radius2_, b, max_leaves_, out, capacity)
                 : f32_.radius_search(q.point, radius2_, b, out, capacity);
    }
    case DescriptorEncoding::kInt16:
      return search_encoded(encoded<std::int16_t>(q), q.box, out, capacity);
    case DescriptorEncoding::kInt8:
      return search_encoded(encoded<std::int8_t>(q), q.box, out, capacity);
  }
  return 0;
}

std::uint32_t ArcSearch::search_keys(const Query& q, std::uint64_t* out,
                                     std::uint32_t capacity) const {
  switch (encoding_) {
    case DescriptorEncoding::kFloat32: {
      const float b = q.box ? static_cast<float>(box_) : std::numeric_limits<float>::max();
      return f32_.radius_search_approximate(q.point, radius2_, b, max_leaves_, keys_, out,
                                            capacity);
    }
    case DescriptorEncoding::kInt16: {
      const std::int64_t b = q.box ? box_ : std::numeric_limits<std::int64_t>::max();
      return i16_.radius_search_approximate(encoded<std::int16_t>(q), radius2_scaled_, b,
                                            max_leaves_, keys_, out, capacity);
    }
    case DescriptorEncoding::kInt8: {
      const std::int32_t b = q.box ? box_ : std::numeric_limits<std::int32_t>::max();
      return i8_.radius_search_approximate(encoded<std::int8_t>(q),
                                           static_cast<ArcTreeView8::Dist>(radius2_scaled_), b,
                                           max_leaves_, keys_, out, capacity);
    }
  }
  return 0;
}

namespace {

// What the tree's leaf scan tests, for one point.
template <class T, class Dist>
bool within(const std::array<T, kSearchDims>& p, const std::array<T, kSearchDims>& q, Dist radius2,
            bool box, Dist half_width) {
  if (!(kd_distance2(p, q) < radius2)) return false;
  if (!box) return true;
  for (int d = kDescriptorSize; d < kSearchDims; ++d) {
    const Dist diff = static_cast<Dist>(p[d]) - static_cast<Dist>(q[d]);
    if ((diff < 0 ? -diff : diff) > half_width) return false;
  }
  return true;
}

}  // namespace

void ArcSearch::prefetch(std::uint32_t slot) const {
#if defined(__GNUC__)
  switch (encoding_) {
    case DescriptorEncoding::kFloat32:
      __builtin_prefetch(points_f32_ + slot);
      break;
    case DescriptorEncoding::kInt16:
      __builtin_prefetch(points_i16_ + slot);
      break;
    case DescriptorEncoding::kInt8:
      __builtin_prefetch(points_i8_ + slot);
      break;
  }
#else
  (void)slot;
#endif
}

bool ArcSearch::matches(const Query& q, std::uint32_t slot) const {
  switch (encoding_) {
    case DescriptorEncoding::kFloat32:
      return within(points_f32_[slot], q.point, radius2_, q.box, static_cast<float>(box_));
    case DescriptorEncoding::kInt16:
      return within(points_i16_[slot], encoded<std::int16_t>(q), radius2_scaled_, q.box,
                    static_cast<std::int64_t>(box_));
    case DescriptorEncoding::kInt8:
      return within(points_i8_[slot], encoded<std::int8_t>(q),
                    static_cast<ArcTreeView8::Dist>(radius2_scaled_), q.box, box_);
  }
  return false;
}

std::uint32_t ArcSearch::search_encoded(const ArcSearchPointI16& p, bool box, std::uint32_t* out,
                                        std::uint32_t capacity) const {
  const std::int64_t b = box ? box_ : std::numeric_limits<std::int64_t>::max();
  return max_leaves_ > 0
             ? i16_.radius_search_approximate(p, radius2_scaled_, b, max_leaves_, out, capacity)
             : i16_.radius_search(p, radius2_scaled_, b, out, capacity);
}

std::uint32_t ArcSearch::search_encoded(const ArcSearchPointI8& p, bool box, std::uint32_t* out,
                                        std::uint32_t capacity) const {
  const auto r2 = static_cast<ArcTreeView8::Dist>(radius2_scaled_);
  const std::int32_t b = box ? box_ : std::numeric_limits<std::int32_t>::max();
  return max_leaves_ > 0 ? i8_.radius_search_approximate(p, r2, b, max_leaves_, out, capacity)
                         : i8_.radius_search(p, r2, b, out, capacity);
}

}  // namespace kg
