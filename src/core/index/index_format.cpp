#include "core/index/index_format.h"

#include "core/description/descriptor_encoding.h"
#include "core/index/kdtree.h"

#include <cmath>
#include <limits>
#include <string>
#include <type_traits>

namespace kg::format {
namespace {

bool finite_positive(double v) {
  return std::isfinite(v) && v > 0.0;
}

Status bad(const std::string& field, const std::string& why) {
  return {StatusCode::kCorruptData, "parameter " + field + " " + why};
}

}  // namespace

const char* section_name(std::uint32_t id) {
  switch (id) {
    case kSectionModels:
      return "models";
    case kSectionStrings:
      return "strings";
    case kSectionKeypoints:
      return "keypoints";
    case kSectionTreeArcs:
      return "tree arcs";
    case kSectionDescriptors:
      return "descriptors";
    case kSectionTreeNodes:
      return "tree nodes";
    case kSectionVertexDescriptors:
      return "vertex descriptors";
    case kSectionKeypointScales:
      return "keypoint scales";
    case kSectionTreeArcTargets:
      return "tree arc targets";
    case kSectionLeafBounds:
      return "leaf bounds";
    case kSectionKeypointViews:
      return "keypoint views";
    case kSectionModelQuality:
      return "model quality";
    case kSectionViewQuality:
      return "view quality";
    case kSectionLookAlikes:
      return "look-alikes";
    case kSectionAppearances:
      return "model appearance";
    case kSectionAppearancePixels:
      return "appearance pixels";
    default:
      return "(unknown)";
  }
}

void serialize_params(const Params& params, std::uint8_t* out) {
  std::memset(out, 0, kParamsSize);
  std::size_t at = 0;
  visit_params(params, [&](const char*, const auto& field) {
    using T = std::decay_t<decltype(field)>;
    if constexpr (std::is_enum_v<T>) {
      out[at] = static_cast<std::uint8_t>(field);
    } else {
      store<T>(out + at, field);
    }
    at += stored_size<T>();
  });
}

Status parse_params(const std::uint8_t* in, std::size_t size, Params& params) {
  if (size < kMinParamsSize) return {StatusCode::kCorruptData, "parameter block too small"};
  std::size_t at = 0;
  visit_params(params, [&](const char*, auto& field) {
    using T = std::decay_t<decltype(field)>;
    if (at + stored_size<T>() > size) {
      field = T{};  // past an older file's block: what its zero tail would hold
    } else if constexpr (std::is_enum_v<T>) {
      field = static_cast<T>(in[at]);
    } else {
      field = load<T>(in + at);
    }
    at += stored_size<T>();
  });
  // Written before the parameter existed: its zero tail means off.
  if (params.keypoints.scene_upsample == 0) params.keypoints.scene_upsample = 1;
  if (params.views.max_scale == 0.f) params.views.max_scale = 1.f;
  return validate_params(params);
}

Status validate_params(const Params& p) {
  const auto detector = static_cast<unsigned>(p.keypoints.detector);
  if (detector > 1)
    return bad("keypoints.detector", "is unknown (" + std::to_string(detector) + ")");
  const int k = static_cast<int>(p.graph.structure);
  if (k < 2 || k > 4) return bad("graph.structure", "must have 2, 3 or 4 vertices");
  if (static_cast<unsigned>(p.graph.scene_sampling) > 1)
    return bad("graph.scene_sampling", "is unknown");
  if (!(std::isfinite(p.graph.max_scale_error) && p.graph.max_scale_error >= 0.f &&
        p.graph.max_scale_error <= 10.f))
    return bad("graph.max_scale_error", "must be in [0, 10]");
  if (!(std::isfinite(p.graph.max_relative_length) && p.graph.max_relative_length >= 0.f))
    return bad("graph.max_relative_length", "must be >= 0");
  if (p.descriptor.max_search_leaves < 0)
    return bad("descriptor.max_search_leaves", "must be >= 0");
  if (!(std::isfinite(p.ransac.min_triangle_correlation) &&
        p.ransac.min_triangle_correlation >= 0.f && p.ransac.min_triangle_correlation < 1.f))
    return bad("ransac.min_triangle_correlation", "must be in [0, 1) (0: off)");
  if (p.ransac.progressive_sampling != 0 && p.ransac.progressive_sampling != 1)
    return bad("ransac.progressive_sampling", "must be 0 (uniform draws) or 1 (progressive)");
  if (p.graph.complete_circuits != 0 && p.graph.complete_circuits != 1)
    return bad("graph.complete_circuits", "must be 0 (off) or 1 (on)");
  if (p.graph.max_neighbour_rank < 0)
    return bad("graph.max_neighbour_rank", "must be >= 0 (0: every pair in range)");
  if (p.descriptor.search_reference_models < 0)
    return bad("descriptor.search_reference_models", "must be >= 0 (0: a fixed search budget)");
  if (!(std::isfinite(p.keypoints.hessian_threshold) && p.keypoints.hessian_threshold >= 0.f))
    return bad("keypoints.hessian_threshold", "must be >= 0");
  if (p.keypoints.hessian_octaves < 1 || p.keypoints.hessian_octaves > 8)
    return bad("keypoints.hessian_octaves", "must be in 1..8");
  if (p.keypoints.hessian_levels < 1 || p.keypoints.hessian_levels > 8)
    return bad("keypoints.hessian_levels", "must be in 1..8");
  if (p.keypoints.hessian_fine_levels < 0 ||
      p.keypoints.hessian_fine_levels > p.keypoints.hessian_levels)
    return bad("keypoints.hessian_fine_levels", "must be in 0..keypoints.hessian_levels");
  if (!(std::isfinite(p.keypoints.hessian_fine_threshold) &&
        p.keypoints.hessian_fine_threshold >= 0.f))
    return bad("keypoints.hessian_fine_threshold", "must be >= 0 (0: keypoints.hessian_threshold)");
  if (p.keypoints.mser_delta < 1 || p.keypoints.mser_min_area < 1 ||
      p.keypoints.mser_max_area < p.keypoints.mser_min_area)
    return bad("keypoints.mser_delta, keypoints.mser_min_area, keypoints.mser_max_area",
               "delta/areas out of range");
  if (p.keypoints.scene_upsample < 1 || p.keypoints.scene_upsample > 4)
    return bad("keypoints.scene_upsample",
               "must be 1 (the frame), 2 (upsampled 2x), 3 (both) or 4 (the frame, then "
               "upsampled where it pays)");
  if (p.keypoints.model_scales < 1 || p.keypoints.model_scales > 8)
    return bad("keypoints.model_scales", "must be in 1..8");
  if (!(std::isfinite(p.keypoints.model_merge_distance) && p.keypoints.model_merge_distance >= 0.f))
    return bad("keypoints.model_merge_distance", "must be >= 0");
  if (p.keypoints.max_model_keypoints < 4 || p.keypoints.max_model_keypoints > kMaxModelKeypoints)
    return bad("keypoints.max_model_keypoints", "must be in 4..32768");
  if (!finite_positive(p.graph.min_distance) || !finite_positive(p.graph.max_distance) ||
      p.graph.max_distance < p.graph.min_distance)
    return bad("graph.min_distance, graph.max_distance", "must be positive with min <= max");
  if (!(std::isfinite(p.graph.max_anisotropy) &&
        (p.graph.max_anisotropy == 0.f || p.graph.max_anisotropy >= 1.f)))
    return bad("graph.max_anisotropy", "must be 0 (off) or >= 1");
  if (!finite_positive(p.graph.scene_sample_distance))
    return bad("graph.scene_sample_distance", "must be positive");
  if (!(std::isfinite(p.descriptor.blur_sigma) && p.descriptor.blur_sigma >= 0.f &&
        p.descriptor.blur_sigma <= 20.f))
    return bad("descriptor.blur_sigma", "must be in [0, 20]");
  if (p.descriptor.profile_length < 4 || p.descriptor.profile_length > 256)
    return bad("descriptor.profile_length", "must be in 4..256");
  if (p.descriptor.coefficients < 1 || p.descriptor.coefficients > kMaxCoefficients ||
      2 * p.descriptor.coefficients >= p.descriptor.profile_length)
    return bad("descriptor.coefficients", "must be in 1.." + std::to_string(kMaxCoefficients));
  if (p.descriptor.parallel_offset < 0 || p.descriptor.parallel_offset > 8)
    return bad("descriptor.parallel_offset", "must be in 0..8");
  if (p.descriptor.subpixel_profiles < 0 || p.descriptor.subpixel_profiles > 1)
    return bad("descriptor.subpixel_profiles", "must be 0 or 1");
  if (!finite_positive(p.descriptor.similarity_threshold) ||
      p.descriptor.similarity_threshold > 2.f)
    return bad("descriptor.similarity_threshold", "must be in (0, 2]");
  if (static_cast<unsigned>(p.descriptor.vertex_descriptor) > 1)
    return bad("descriptor.vertex_descriptor",
               "is unknown (" +
                   std::to_string(static_cast<unsigned>(p.descriptor.vertex_descriptor)) + ")");
  // 0 is allowed without vertex descriptors (the value is then unused).
  if (!(std::isfinite(p.descriptor.vertex_threshold) && p.descriptor.vertex_threshold >= 0.f &&
        p.descriptor.vertex_threshold <= 2.f) ||
      (p.descriptor.vertex_descriptor != VertexDescriptor::kNone &&
       p.descriptor.vertex_threshold == 0.f))
    return bad("descriptor.vertex_threshold", "must be in (0, 2]");
  const auto encoding = static_cast<unsigned>(p.descriptor.encoding);
  if (encoding > 2)
    return bad("descriptor.encoding", "is unknown (" + std::to_string(encoding) + ")");
  // The similarity radius must fit the integer search's squared distances.
  std::int64_t scaled = 0;
  const std::int64_t limit = p.descriptor.encoding == DescriptorEncoding::kInt8
                                 ? std::numeric_limits<KdTraits<std::int8_t>::Dist>::max()
                                 : std::numeric_limits<KdTraits<std::int16_t>::Dist>::max();
  if (p.descriptor.encoding != DescriptorEncoding::kFloat32 &&
      !scaled_radius2(p.descriptor.similarity_threshold, p.descriptor.encoding, limit, scaled))
    return bad("descriptor.similarity_threshold", "overflows the encoding's squared distances");
  if (!(p.ransac.confidence > 0.0 && p.ransac.confidence < 1.0))
    return bad("ransac.confidence", "must be in (0, 1)");
  if (p.ransac.max_iterations < 1 || p.ransac.max_iterations > 10000000)
    return bad("ransac.max_iterations", "must be in 1..10^7");
  if (!finite_positive(p.ransac.inlier_threshold))
    return bad("ransac.inlier_threshold", "must be positive");
  if (p.ransac.min_inliers < 4) return bad("ransac.min_inliers", "must be >= 4");
  if (p.ransac.min_inlier_keygraphs < 1) return bad("ransac.min_inlier_keygraphs", "must be >= 1");
  if (!(std::isfinite(p.ransac.max_scale_change) && p.ransac.max_scale_change >= 1.0))
    return bad("ransac.max_scale_change", "must be >= 1");
  if (!finite_positive(p.ransac.max_perspective))
    return bad("ransac.max_perspective", "must be positive");
  if (!(std::isfinite(p.ransac.min_verification_z) && p.ransac.min_verification_z >= 0.0))
    return bad("ransac.min_verification_z", "must be >= 0");
  if (p.ransac.max_instances < 1 || p.ransac.max_instances > 64)
    return bad("ransac.max_instances", "must be in 1..64");
  if (!(std::isfinite(p.views.min_size) && p.views.min_size >= 0.f && p.views.min_size <= 100000.f))
    return bad("views.min_size", "must be in [0, 100000] (0: no views)");
  if (!(std::isfinite(p.views.scale_step) && p.views.scale_step >= 0.3f &&
        p.views.scale_step <= 0.95f))
    return bad("views.scale_step", "must be in [0.3, 0.95]");
  if (!(std::isfinite(p.views.max_tilt) && p.views.max_tilt >= 0.f && p.views.max_tilt <= 80.f))
    return bad("views.max_tilt", "must be in [0, 80] degrees");
  if (!(std::isfinite(p.views.max_scale) && p.views.max_scale >= 1.f && p.views.max_scale <= 4.f))
    return bad("views.max_scale", "must be in [1, 4] (1: no views larger than the model image)");
  // A view s times larger than the model shows it at area scale s^2: above
  // ransac.max_scale_change the pose check refuses every pose it could give.
  if (static_cast<double>(p.views.max_scale) * p.views.max_scale >
      p.ransac.max_scale_change * 1.002)
    return bad("views.max_scale",
               "must be at most sqrt(ransac.max_scale_change) (the pose check refuses the poses of "
               "larger views)");
  if (p.views.tilt_levels < 0 || p.views.tilt_levels > 8)
    return bad("views.tilt_levels", "must be in 0..8");
  if (!(std::isfinite(p.views.merge_distance) && p.views.merge_distance >= 0.f &&
        p.views.merge_distance <= 10.f))
    return bad("views.merge_distance", "must be in [0, 10]");
  if (!(std::isfinite(p.views.dedupe_distance) && p.views.dedupe_distance >= 0.f &&
        p.views.dedupe_distance <= 2.f))
    return bad("views.dedupe_distance", "must be in [0, 2]");
  if (p.views.appearance_size < 0 || p.views.appearance_size > kMaxAppearanceSize ||
      (p.views.appearance_size > 0 && p.views.appearance_size < kMinAppearanceSize))
    return bad("views.appearance_size", "must be 0 (none) or in " +
                                            std::to_string(kMinAppearanceSize) + ".." +
                                            std::to_string(kMaxAppearanceSize));
  if (!(std::isfinite(p.ransac.min_appearance) && p.ransac.min_appearance >= -1.f &&
        p.ransac.min_appearance <= 1.f))
    return bad("ransac.min_appearance", "must be in [-1, 1]");
  if (p.ransac.confirmed_min_inliers != 0 &&
      (p.ransac.confirmed_min_inliers < 4 || p.ransac.confirmed_min_inliers > 100000))
    return bad("ransac.confirmed_min_inliers", "must be 0 (never) or in 4..100000");
  if (!(std::isfinite(p.ransac.confirmed_min_verification_z) &&
        p.ransac.confirmed_min_verification_z >= 0.f &&
        p.ransac.confirmed_min_verification_z <= 1000.f))
    return bad("ransac.confirmed_min_verification_z", "must be in [0, 1000]");
  if (!(std::isfinite(p.ransac.confirmed_min_appearance) &&
        p.ransac.confirmed_min_appearance >= -1.f && p.ransac.confirmed_min_appearance <= 1.f))
    return bad("ransac.confirmed_min_appearance", "must be in [-1, 1]");
  if (!(std::isfinite(p.ransac.small_max_size) && p.ransac.small_max_size >= 0.f &&
        p.ransac.small_max_size <= 100000.f))
    return bad("ransac.small_max_size", "must be in [0, 100000] (0: off)");
  if (p.ransac.small_min_inliers != 0 &&
      (p.ransac.small_min_inliers < 4 || p.ransac.small_min_inliers > 100000))
    return bad("ransac.small_min_inliers", "must be 0 (off) or in 4..100000");
  if (!(std::isfinite(p.ransac.small_min_appearance) && p.ransac.small_min_appearance >= -1.f &&
        p.ransac.small_min_appearance <= 1.f))
    return bad("ransac.small_min_appearance", "must be in [-1, 1]");
  if (!(std::isfinite(p.views.blurred_max_size) && p.views.blurred_max_size >= 0.f &&
        p.views.blurred_max_size <= 100000.f))
    return bad("views.blurred_max_size", "must be in [0, 100000] (0: off)");
  if (!(std::isfinite(p.views.glow_max_size) && p.views.glow_max_size >= 0.f &&
        p.views.glow_max_size <= 100000.f))
    return bad("views.glow_max_size", "must be in [0, 100000] (0: off)");
  return Status::ok();
}

}  // namespace kg::format
