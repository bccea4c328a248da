// Byte layout of the .kgi model index, shared by the reader (core) and the
// writer (desktop builder). docs/FORMAT.md is the specification; every
// number here is little-endian and fixed-width.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "core/description/arc_types.h"
#include "keygraph/params.h"
#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg::format {

// PNG-style magic: the high-bit byte catches 7-bit transfers, CR LF and the
// SUB/LF tail catch text-mode conversions and `type` on DOS.
inline constexpr std::uint8_t kMagic[8] = {0x89, 'K', 'G', 'I', '\r', '\n', 0x1A, '\n'};
// 2.0: arcs in tree order (no tree-id section), encoded descriptors.
// 3.0: keypoint scales (section 8), graph.max_scale_error, and tree points
// of descriptor plus scale attributes (kSearchDims components).
// 4.0: scale attributes on a 1/16-log grid, leaf bounds.
// 5.0: search-tree leaves of up to 64 arcs (kLeafSize; 4.x: 32).
// 6.0: model views (parameters views.*; arcs and their scale attributes
// from simulated views) and the keypoint views section (11).
// 6.1: the model quality report (sections 12-14); 6.0 files have none.
// 6.2: each model's appearance (sections 15-16, parameters
// views.appearance_size, ransac.min_appearance and ransac.confirmed_*);
// older files have none.
// 6.3: descriptor.search_reference_models (the search budget grows with
// the index's models); older files read it as 0, a fixed budget, as they were searched.
inline constexpr std::uint16_t kVersionMajor = 6;
// 6.4: ransac.min_triangle_correlation (the triangle patch check of each
// correspondence) and ransac.progressive_sampling (PROSAC); older files read
// them as 0, off, as they were matched and sampled.
// 6.5: graph.complete_circuits (3-circuits from two searched arcs and a
// direct check of the third); older files read it as 0, off.
// 6.6: graph.max_neighbour_rank (model arcs join near neighbours only);
// older files read it as 0, every pair in range, as they were built.
// 6.7: views.max_scale (views larger than the model image); older files
// read it as 1, none, as they were built.
// 6.8: keypoints.hessian_fine_levels and hessian_fine_threshold (Hessian
// levels below the first octave's, issue 38); older files read them as 0,
// no fine levels, as they were built.
// 6.9: descriptor.subpixel_profiles (arc profiles sampled at the keypoints'
// sub-pixel positions, opt-in, issue 38); older files read it as 0, the
// Bresenham profiles they were built with.
// 6.10: ransac.small_max_size, small_min_inliers and small_min_appearance
// (poses of small instances kept with fewer inliers when their appearance
// confirms them, issue 38); older files read them as 0, off.
// 6.11: views.blurred_max_size (blurred twins of the small model views,
// opt-in, issue 38), the first field past 256 bytes: the parameter block
// is 320 bytes; older files read it as 0, off, as they were built.
// 6.12: views.glow_max_size (glowing twins of the small model views,
// opt-in, issue 38); older files read it as 0, off, as they were built.
inline constexpr std::uint16_t kVersionMinor = 12;
inline constexpr std::size_t kAlignment = 64;

inline constexpr std::size_t kHeaderSize = 64;
// Header fields (byte offsets).
inline constexpr std::size_t kOffMagic = 0;
inline constexpr std::size_t kOffMajor = 8;
inline constexpr std::size_t kOffMinor = 10;
inline constexpr std::size_t kOffHeaderSize = 12;
inline constexpr std::size_t kOffFileSize = 16;
inline constexpr std::size_t kOffParamsOffset = 24;
inline constexpr std::size_t kOffParamsSize = 28;
inline constexpr std::size_t kOffTableOffset = 32;
inline constexpr std::size_t kOffSectionCount = 36;
inline constexpr std::size_t kOffHeaderCrc = 40;  // CRC-32 of [0, table end) with this field 0

// Every file's parameter block is at least this long (readers since 2.0
// refuse a shorter one); kParamsSize, the block this writer writes, is
// below the parameter list.
inline constexpr std::size_t kMinParamsSize = 256;
inline constexpr std::size_t kSectionEntrySize = 32;
// Section table entry fields (byte offsets within an entry).
inline constexpr std::size_t kEntId = 0;
inline constexpr std::size_t kEntEncoding = 4;
inline constexpr std::size_t kEntOffset = 8;
inline constexpr std::size_t kEntSize = 16;
inline constexpr std::size_t kEntCount = 24;
inline constexpr std::size_t kEntCrc = 28;

enum SectionId : std::uint32_t {
  kSectionModels = 1,             // ModelRecord per model
  kSectionStrings = 2,            // UTF-8 model names
  kSectionKeypoints = 3,          // float32 x, y per keypoint
  kSectionTreeArcs = 4,           // uint32 `from` per tree slot (global keypoint id)
  kSectionDescriptors = 5,        // per tree slot: kSearchDims components, encoded
  kSectionTreeNodes = 6,          // split and dimension per internal node, encoded
  kSectionVertexDescriptors = 7,  // kVertexDescriptorSize bytes (SIFT) per keypoint, or empty
  kSectionKeypointScales = 8,     // float32 detector scale (sigma, model pixels) per keypoint
  kSectionTreeArcTargets = 9,     // int16 `to - from` per tree slot
  kSectionLeafBounds = 10,        // per tree leaf: minimum and maximum tree point, encoded
  kSectionKeypointViews = 11,     // u8 finest, u8 coarsest view scale code per keypoint
  kSectionModelQuality = 12,      // quality record per model (6.1), or empty: no report
  kSectionViewQuality = 13,       // quality record per model view (6.1)
  kSectionLookAlikes = 14,        // (shown, detected) model pairs (6.1)
  kSectionAppearances = 15,       // appearance record per model (6.2), or empty: none
  kSectionAppearancePixels = 16,  // 8-bit grey pixels of every model's appearance (6.2)
};
// Sections 1..kSectionCount are in every index and required (empty ones
// included); from minor version 1 on, sections 12..14 too, and from minor
// version 2 on, 15..kLastSectionId. Ids above are skipped by the reader:
// room for later minor versions.
inline constexpr std::uint32_t kSectionCount = 11;
inline constexpr std::uint32_t kLastSectionId = 16;
// The last section id a file of minor version `minor` must have.
inline constexpr std::uint32_t last_required_section(std::uint16_t minor) {
  return minor >= 2 ? kSectionAppearancePixels : minor == 1 ? kSectionLookAlikes : kSectionCount;
}

// View scale codes (section 11): code = round(-log2(scale) * 8), 0 for the
// model image's own scale, one step per eighth of an octave; the scale of a
// tilted view is its area scale, sqrt(scale^2 / tilt). A keypoint detected
// in no view but kept (the paper's model, without views) spans 0..255.
inline constexpr float kViewCodesPerOctave = 8.f;
// A model has at most this many keypoints, so that an arc's `to - from`
// fits the int16 of section 9.
inline constexpr int kMaxModelKeypoints = 32768;

// "models", "tree arcs", ... (error messages, keygraph inspect);
// "(unknown)" for other ids.
const char* section_name(std::uint32_t id);

// Bytes per tree node: f32 split + u32 dimension (float32), i16 split + u16
// dimension (int16, int8).
inline constexpr std::size_t tree_node_size(DescriptorEncoding e) {
  return e == DescriptorEncoding::kFloat32 ? 8 : 4;
}

// Model record (kModelRecordSize bytes).
inline constexpr std::size_t kModelRecordSize = 80;
inline constexpr std::size_t kModNameOffset = 0;
inline constexpr std::size_t kModNameLength = 4;
inline constexpr std::size_t kModWidth = 8;
inline constexpr std::size_t kModHeight = 12;
inline constexpr std::size_t kModKeypointBegin = 16;
inline constexpr std::size_t kModKeypointCount = 20;
inline constexpr std::size_t kModArcCount = 24;  // arcs leaving the model's keypoints
inline constexpr std::size_t kModReserved = 28;  // u32, zero
inline constexpr std::size_t kModKeygraphCount = 32;
inline constexpr std::size_t kModOutline = 40;  // 8 x float32, then 8 reserved bytes

// Model quality record (section 12, kModelQualitySize bytes), one per model
// in model order.
inline constexpr std::size_t kModelQualitySize = 32;
inline constexpr std::size_t kMqViewBegin = 0;      // u32, first record of section 13
inline constexpr std::size_t kMqViewCount = 4;      // u32
inline constexpr std::size_t kMqSharedArcs = 8;     // u32, arcs with a near-identical arc elsewhere
inline constexpr std::size_t kMqSmallestSize = 12;  // f32, long edge in px (0: no view)
inline constexpr std::size_t kMqSceneSize = 16;     // f32, long edge of its scene (0: not rendered)
inline constexpr std::size_t kMqFlags = 20;         // u32, kQuality* bits
inline constexpr std::size_t kMqReserved = 24;      // 8 bytes, zero
inline constexpr std::uint32_t kQualityFoundInScene = 1;  // detected in its own scene
inline constexpr std::uint32_t kQualityFlagsKnown = kQualityFoundInScene;
// View quality record (section 13, kViewQualitySize bytes).
inline constexpr std::size_t kViewQualitySize = 24;
inline constexpr std::size_t kVqScale = 0;       // f32, (0, views.max_scale]
inline constexpr std::size_t kVqTilt = 4;        // f32, >= 1
inline constexpr std::size_t kVqLongitude = 8;   // f32, degrees in [0, 180)
inline constexpr std::size_t kVqKeypoints = 12;  // u32
inline constexpr std::size_t kVqArcs = 16;       // u32
inline constexpr std::size_t kVqKeygraphs = 20;  // u32, saturated
// Look-alike record (section 14, kLookAlikeSize bytes): u32 the model whose
// scene was rendered, u32 the other model detected in it; sorted, distinct.
inline constexpr std::size_t kLookAlikeSize = 8;

// Appearance record (section 15, kAppearanceSize bytes), one per model in
// model order when views.appearance_size > 0, else none. The pixels
// (section 16) are the appearances row-major without padding, models
// consecutive in model order.
inline constexpr std::size_t kAppearanceSize = 16;
inline constexpr std::size_t kApWidth = 0;        // u32, 1..appearance_size
inline constexpr std::size_t kApHeight = 4;       // u32, 1..appearance_size
inline constexpr std::size_t kApScale = 8;        // f32, (0, 1]: appearance px per model px
inline constexpr std::size_t kApFirstPixel = 12;  // u32, offset into section 16
inline constexpr int kMaxAppearanceSize = 512;    // largest views.appearance_size
inline constexpr int kMinAppearanceSize = 16;     // smallest non-zero views.appearance_size

inline std::size_t align_up(std::size_t v) {
  return (v + kAlignment - 1) & ~(kAlignment - 1);
}

// Little-endian fixed-width access (the only byte order keygraph runs on,
// checked at load time).
template <class T>
inline T load(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}
template <class T>
inline void store(std::uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof(T));
}

// The one place that lists the parameters, in their order in the file, with
// their names (as `--set NAME=VALUE` and `keygraph inspect` spell them):
// writer, reader and inspector all walk it, so they cannot disagree. Calls
// f(name, field) per field; P is Params or const Params.
template <class P, class F>
constexpr void visit_params(P& p, F&& f) {
  f("keypoints.detector", p.keypoints.detector);
  f("graph.structure", p.graph.structure);
  f("graph.scene_sampling", p.graph.scene_sampling);
  f("keypoints.hessian_threshold", p.keypoints.hessian_threshold);
  f("keypoints.hessian_octaves", p.keypoints.hessian_octaves);
  f("keypoints.hessian_levels", p.keypoints.hessian_levels);
  f("keypoints.mser_delta", p.keypoints.mser_delta);
  f("keypoints.mser_min_area", p.keypoints.mser_min_area);
  f("keypoints.mser_max_area", p.keypoints.mser_max_area);
  f("keypoints.model_scales", p.keypoints.model_scales);
  f("keypoints.model_merge_distance", p.keypoints.model_merge_distance);
  f("keypoints.max_model_keypoints", p.keypoints.max_model_keypoints);
  f("graph.min_distance", p.graph.min_distance);
  f("graph.max_distance", p.graph.max_distance);
  f("graph.scene_sample_distance", p.graph.scene_sample_distance);
  f("graph.max_anisotropy", p.graph.max_anisotropy);
  f("descriptor.blur_sigma", p.descriptor.blur_sigma);
  f("descriptor.profile_length", p.descriptor.profile_length);
  f("descriptor.coefficients", p.descriptor.coefficients);
  f("descriptor.parallel_offset", p.descriptor.parallel_offset);
  f("descriptor.similarity_threshold", p.descriptor.similarity_threshold);
  f("ransac.confidence", p.ransac.confidence);
  f("ransac.max_iterations", p.ransac.max_iterations);
  f("ransac.inlier_threshold", p.ransac.inlier_threshold);
  f("ransac.min_inliers", p.ransac.min_inliers);
  f("ransac.min_inlier_keygraphs", p.ransac.min_inlier_keygraphs);
  f("ransac.max_scale_change", p.ransac.max_scale_change);
  f("ransac.max_perspective", p.ransac.max_perspective);
  f("ransac.max_instances", p.ransac.max_instances);
  f("ransac.min_verification_z", p.ransac.min_verification_z);
  f("ransac.seed", p.ransac.seed);
  f("descriptor.vertex_descriptor", p.descriptor.vertex_descriptor);
  f("descriptor.vertex_threshold", p.descriptor.vertex_threshold);
  f("descriptor.encoding", p.descriptor.encoding);
  f("graph.max_scale_error", p.graph.max_scale_error);
  f("graph.max_relative_length", p.graph.max_relative_length);
  f("descriptor.max_search_leaves", p.descriptor.max_search_leaves);
  f("views.min_size", p.views.min_size);
  f("views.scale_step", p.views.scale_step);
  f("views.max_tilt", p.views.max_tilt);
  f("views.tilt_levels", p.views.tilt_levels);
  f("views.merge_distance", p.views.merge_distance);
  f("views.dedupe_distance", p.views.dedupe_distance);
  f("views.appearance_size", p.views.appearance_size);                              // 6.2
  f("ransac.min_appearance", p.ransac.min_appearance);                              // 6.2
  f("ransac.confirmed_min_inliers", p.ransac.confirmed_min_inliers);                // 6.2
  f("ransac.confirmed_min_verification_z", p.ransac.confirmed_min_verification_z);  // 6.2
  f("ransac.confirmed_min_appearance", p.ransac.confirmed_min_appearance);          // 6.2
  f("descriptor.search_reference_models", p.descriptor.search_reference_models);    // 6.3
  f("keypoints.scene_upsample", p.keypoints.scene_upsample);  // 6.3; 0 in older files: read as 1
  f("ransac.min_triangle_correlation", p.ransac.min_triangle_correlation);  // 6.4; 0: off
  f("ransac.progressive_sampling", p.ransac.progressive_sampling);          // 6.4; 0: off
  f("graph.complete_circuits", p.graph.complete_circuits);                  // 6.5; 0: off
  f("graph.max_neighbour_rank", p.graph.max_neighbour_rank);  // 6.6; 0: every pair in range
  f("views.max_scale", p.views.max_scale);                    // 6.7; 0 in older files: read as 1
  f("keypoints.hessian_fine_levels", p.keypoints.hessian_fine_levels);        // 6.8; 0: off
  f("keypoints.hessian_fine_threshold", p.keypoints.hessian_fine_threshold);  // 0: the threshold
  f("descriptor.subpixel_profiles", p.descriptor.subpixel_profiles);          // 6.9; 0: Bresenham
  f("ransac.small_max_size", p.ransac.small_max_size);                        // 6.10; 0: off
  f("ransac.small_min_inliers", p.ransac.small_min_inliers);                  // 6.10; 0: off
  f("ransac.small_min_appearance", p.ransac.small_min_appearance);            // 6.10
  f("views.blurred_max_size", p.views.blurred_max_size);                      // 6.11; 0: off
  f("views.glow_max_size", p.views.glow_max_size);                            // 6.12; 0: off
  // Later minor versions append here; the block's zero tail is what an
  // older file holds for them, and a field past the end of an older file's
  // (shorter) block reads as zero too.
}

// Bytes a field of type T takes in the block: enumerations one, the rest
// their size.
template <class T>
constexpr std::size_t stored_size() {
  if constexpr (std::is_enum_v<T>) {
    return 1;
  } else {
    return sizeof(T);
  }
}

// Bytes of every field, packed.
constexpr std::size_t params_field_bytes() {
  const Params defaults{};
  std::size_t bytes = 0;
  visit_params(defaults, [&bytes](const char*, const auto& field) {
    bytes += stored_size<std::decay_t<decltype(field)>>();
  });
  return bytes;
}

// The block this writer writes: the fields and a zero tail, a multiple of
// 64 bytes and at least kMinParamsSize. The block grows by 64 bytes when the
// fields outgrow it; the header's size field says how long a file's block is.
inline constexpr std::size_t kParamsSize =
    params_field_bytes() <= kMinParamsSize ? kMinParamsSize : (params_field_bytes() + 63) / 64 * 64;

// Parameters block <-> Params. parse_params validates every value.
void serialize_params(const Params& params, std::uint8_t* out /* kParamsSize bytes */);
Status parse_params(const std::uint8_t* in, std::size_t size, Params& params);
// Same checks for parameters given programmatically (builder, CLI).
Status validate_params(const Params& params);

}  // namespace kg::format
