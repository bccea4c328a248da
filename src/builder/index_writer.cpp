#include "builder/index_writer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <system_error>
#include <type_traits>
#include <unordered_map>

#include "core/description/arc_attributes.h"
#include "core/description/arc_types.h"
#include "core/description/descriptor_encoding.h"
#include "core/index/crc32.h"
#include "core/index/index_format.h"
#include "core/index/kdtree.h"
#include "platform/files/output_file.h"

namespace kg {

namespace {

template <class T>
constexpr DescriptorEncoding encoding_of() {
  if constexpr (std::is_same_v<T, std::int16_t>) {
    return DescriptorEncoding::kInt16;
  } else if constexpr (std::is_same_v<T, std::int8_t>) {
    return DescriptorEncoding::kInt8;
  } else {
    return DescriptorEncoding::kFloat32;
  }
}

// The search tree over `descriptors` in the domain of T: quantised (int16,
// int8) or as computed (float), the arcs permuted into tree order.
template <class T>
void encode_tree(const std::vector<ArcSearchPoint>& search_points, double attribute_weight,
                 std::vector<ModelArc>& arcs, std::vector<std::uint8_t>& points_bytes,
                 std::vector<std::uint8_t>& node_bytes, std::vector<std::uint8_t>& bound_bytes) {
  using Point = KdPoint<T, kSearchDims>;
  std::vector<Point> source(search_points.size());
  for (std::size_t i = 0; i < search_points.size(); ++i) {
    if constexpr (std::is_same_v<T, float>) {
      source[i] = search_points[i];
    } else {
      source[i] = encode_point<T>(search_points[i]);
    }
  }
  std::vector<Point> points;
  std::vector<std::uint32_t> ids;
  std::vector<typename KdTraits<T>::Node> nodes;
  build_kdtree<T, kSearchDims>(source.data(), static_cast<std::uint32_t>(source.size()), points,
                               ids, nodes, attribute_weight);
  std::vector<ModelArc> ordered(arcs.size());
  for (std::size_t slot = 0; slot < ids.size(); ++slot) ordered[slot] = arcs[ids[slot]];
  arcs.swap(ordered);
  points_bytes.resize(points.size() * sizeof(Point));
  if (!points.empty()) std::memcpy(points_bytes.data(), points.data(), points_bytes.size());
  std::vector<Point> bounds;
  kdtree_leaf_bounds<T, kSearchDims>(points.data(), static_cast<std::uint32_t>(points.size()),
                                     bounds);
  bound_bytes.resize(bounds.size() * sizeof(Point));
  std::memcpy(bound_bytes.data(), bounds.data(), bound_bytes.size());
  // Nodes field by field: no padding bytes of the struct reach the file.
  node_bytes.assign(nodes.size() * format::tree_node_size(encoding_of<T>()), 0);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    std::uint8_t* p = node_bytes.data() + i * format::tree_node_size(encoding_of<T>());
    if constexpr (std::is_same_v<T, float>) {
      format::store<float>(p, nodes[i].split);
      format::store<std::uint32_t>(p + 4, nodes[i].dim);
    } else {
      format::store<std::int16_t>(p, nodes[i].split);
      format::store<std::uint16_t>(p + 2, nodes[i].dim);
    }
  }
}

}  // namespace

namespace {

// Sections 12-14 of `quality` (empty without one), checked against the
// models as the reader will check them.
Status encode_quality(const std::vector<BuiltModel>& models, const QualityReport* quality,
                      std::vector<std::uint8_t>& model_bytes, std::vector<std::uint8_t>& view_bytes,
                      std::vector<std::uint8_t>& pair_bytes) {
  using namespace format;
  model_bytes.clear();
  view_bytes.clear();
  pair_bytes.clear();
  if (quality == nullptr) return Status::ok();
  const auto invalid = [](const std::string& what) {
    return Status{StatusCode::kInvalidArgument, "quality report: " + what};
  };
  if (quality->models.size() != models.size()) return invalid("one record per model expected");
  std::uint32_t next_view = 0;
  model_bytes.assign(models.size() * kModelQualitySize, 0);
  for (std::size_t m = 0; m < models.size(); ++m) {
    const ModelQuality& q = quality->models[m];
    if (q.view_begin != next_view || q.view_count > quality->views.size() - next_view)
      return invalid("view ranges not consecutive");
    if (q.shared_arcs > models[m].arcs.size()) return invalid("more shared arcs than arcs");
    next_view += q.view_count;
    std::uint8_t* r = model_bytes.data() + m * kModelQualitySize;
    store<std::uint32_t>(r + kMqViewBegin, q.view_begin);
    store<std::uint32_t>(r + kMqViewCount, q.view_count);
    store<std::uint32_t>(r + kMqSharedArcs, q.shared_arcs);
    store<float>(r + kMqSmallestSize, q.smallest_size);
    store<float>(r + kMqSceneSize, q.scene_size);
    store<std::uint32_t>(r + kMqFlags, q.found_in_scene ? kQualityFoundInScene : 0u);
  }
  if (next_view != quality->views.size()) return invalid("views not covered by the models");
  view_bytes.assign(quality->views.size() * kViewQualitySize, 0);
  for (std::size_t v = 0; v < quality->views.size(); ++v) {
    const ViewQuality& q = quality->views[v];
    std::uint8_t* r = view_bytes.data() + v * kViewQualitySize;
    store<float>(r + kVqScale, q.scale);
    store<float>(r + kVqTilt, q.tilt);
    store<float>(r + kVqLongitude, q.longitude);
    store<std::uint32_t>(r + kVqKeypoints, q.keypoints);
    store<std::uint32_t>(r + kVqArcs, q.arcs);
    store<std::uint32_t>(r + kVqKeygraphs, q.keygraphs);
  }
  pair_bytes.assign(quality->look_alikes.size() * kLookAlikeSize, 0);
  for (std::size_t i = 0; i < quality->look_alikes.size(); ++i) {
    const LookAlike& p = quality->look_alikes[i];
    if (p.shown >= models.size() || p.detected >= models.size() || p.shown == p.detected)
      return invalid("look-alike of an unknown model or of itself");
    if (i > 0) {
      const LookAlike& prev = quality->look_alikes[i - 1];
      if (prev.shown > p.shown || (prev.shown == p.shown && prev.detected >= p.detected))
        return invalid("look-alikes not sorted or repeated");
    }
    store<std::uint32_t>(pair_bytes.data() + i * kLookAlikeSize, p.shown);
    store<std::uint32_t>(pair_bytes.data() + i * kLookAlikeSize + 4, p.detected);
  }
  return Status::ok();
}

// Sections 15-16: every model's appearance when the parameters ask for
// them (empty when views.appearance_size is 0), checked as the reader will
// check them.
Status encode_appearances(const std::vector<BuiltModel>& models, const Params& params,
                          std::vector<std::uint8_t>& record_bytes,
                          std::vector<std::uint8_t>& pixel_bytes) {
  using namespace format;
  record_bytes.clear();
  pixel_bytes.clear();
  const int size = params.views.appearance_size;
  if (size == 0) return Status::ok();
  record_bytes.assign(models.size() * kAppearanceSize, 0);
  for (std::size_t m = 0; m < models.size(); ++m) {
    const BuiltModel& model = models[m];
    const cv::Mat& a = model.appearance;
    const int long_edge = std::max(model.width, model.height);
    const int want = std::min(size, long_edge);
    if (a.empty() || a.type() != CV_8UC1 || std::max(a.cols, a.rows) != want ||
        !(model.appearance_scale > 0.f && model.appearance_scale <= 1.f) ||
        (model.appearance_scale < 1.f) != (long_edge > size))
      return {StatusCode::kInvalidArgument,
              model.name + ": no appearance of " + std::to_string(want) +
                  " px on its long edge (build the model with the parameters of the index: "
                  "views.appearance_size " +
                  std::to_string(size) + ")"};
    if (pixel_bytes.size() + a.total() > 0xFFFFFFFFu)
      return {StatusCode::kInvalidArgument, "more than 2^32 - 1 appearance pixels"};
    std::uint8_t* r = record_bytes.data() + m * kAppearanceSize;
    store<std::uint32_t>(r + kApWidth, static_cast<std::uint32_t>(a.cols));
    store<std::uint32_t>(r + kApHeight, static_cast<std::uint32_t>(a.rows));
    store<float>(r + kApScale, model.appearance_scale);
    store<std::uint32_t>(r + kApFirstPixel, static_cast<std::uint32_t>(pixel_bytes.size()));
    for (int y = 0; y < a.rows; ++y) {
      const std::uint8_t* row = a.ptr<std::uint8_t>(y);
      pixel_bytes.insert(pixel_bytes.end(), row, row + a.cols);
    }
  }
  return Status::ok();
}

}  // namespace

Status serialize_index(const std::vector<BuiltModel>& models, const Params& params,
                       std::vector<std::uint8_t>& bytes, const QualityReport* quality) {
  using namespace format;
  Status s = validate_params(params);
  if (!s) return s;
  if (models.empty()) return {StatusCode::kInvalidArgument, "no models to write"};
  std::vector<std::uint8_t> quality_bytes, view_quality_bytes, look_alike_bytes;
  s = encode_quality(models, quality, quality_bytes, view_quality_bytes, look_alike_bytes);
  if (!s) return s;
  std::vector<std::uint8_t> appearance_bytes, appearance_pixels;
  s = encode_appearances(models, params, appearance_bytes, appearance_pixels);
  if (!s) return s;

  // Gather global arrays.
  std::vector<std::uint8_t> records(models.size() * kModelRecordSize, 0);
  std::string strings;
  std::vector<Point2f> keypoints;
  std::vector<float> keypoint_scales;
  std::vector<std::uint8_t> keypoint_views;
  std::vector<ModelArc> arcs;
  std::vector<ArcDescriptor> descriptors;
  std::vector<std::uint8_t> vertex_descriptors;
  const bool with_vertex = params.descriptor.vertex_descriptor != VertexDescriptor::kNone;
  for (std::size_t m = 0; m < models.size(); ++m) {
    const BuiltModel& model = models[m];
    if (model.name.empty()) return {StatusCode::kInvalidArgument, "model with an empty name"};
    if (with_vertex && model.vertex_descriptors.size() !=
                           model.keypoints.size() * static_cast<std::size_t>(kVertexDescriptorSize))
      return {StatusCode::kInvalidArgument,
              model.name +
                  ": no vertex descriptors for every keypoint (build the model with "
                  "the parameters of the index)"};
    if (model.keypoint_scales.size() != model.keypoints.size())
      return {StatusCode::kInvalidArgument, model.name + ": one scale per keypoint expected"};
    if (!model.keypoint_views.empty() && model.keypoint_views.size() != model.keypoints.size())
      return {StatusCode::kInvalidArgument, model.name + ": one view range per keypoint expected"};
    if (model.descriptors.size() != model.arcs.size())
      return {StatusCode::kInvalidArgument, model.name + ": one descriptor per arc expected"};
    std::uint8_t* r = records.data() + m * kModelRecordSize;
    const auto kp_begin = static_cast<std::uint32_t>(keypoints.size());
    store<std::uint32_t>(r + kModNameOffset, static_cast<std::uint32_t>(strings.size()));
    store<std::uint32_t>(r + kModNameLength, static_cast<std::uint32_t>(model.name.size()));
    store<float>(r + kModWidth, static_cast<float>(model.width));
    store<float>(r + kModHeight, static_cast<float>(model.height));
    store<std::uint32_t>(r + kModKeypointBegin, kp_begin);
    store<std::uint32_t>(r + kModKeypointCount, static_cast<std::uint32_t>(model.keypoints.size()));
    store<std::uint32_t>(r + kModArcCount, static_cast<std::uint32_t>(model.arcs.size()));
    store<std::uint64_t>(r + kModKeygraphCount, model.keygraphs);
    // Outline: the image rectangle through the pixel centres of its corners,
    // clockwise on screen.
    const float w = static_cast<float>(model.width - 1), h = static_cast<float>(model.height - 1);
    const float outline[8] = {0.f, 0.f, w, 0.f, w, h, 0.f, h};
    for (int c = 0; c < 8; ++c) store<float>(r + kModOutline + 4 * c, outline[c]);
    strings += model.name;
    keypoints.insert(keypoints.end(), model.keypoints.begin(), model.keypoints.end());
    keypoint_scales.insert(keypoint_scales.end(), model.keypoint_scales.begin(),
                           model.keypoint_scales.end());
    for (std::size_t k = 0; k < model.keypoints.size(); ++k) {
      const bool known = !model.keypoint_views.empty();
      keypoint_views.push_back(known ? model.keypoint_views[k][0] : 0);
      keypoint_views.push_back(known ? model.keypoint_views[k][1] : 255);
    }
    for (const ModelArc& a : model.arcs) arcs.push_back({a.from + kp_begin, a.to + kp_begin});
    descriptors.insert(descriptors.end(), model.descriptors.begin(), model.descriptors.end());
    if (with_vertex)
      vertex_descriptors.insert(vertex_descriptors.end(), model.vertex_descriptors.begin(),
                                model.vertex_descriptors.end());
  }
  if (arcs.size() > 0xFFFFFFFFu || keypoints.size() > 0xFFFFFFFFu)
    return {StatusCode::kInvalidArgument, "more than 2^32 - 1 arcs or keypoints"};
  // Tree points: each descriptor with its arc's scale attributes.
  std::vector<ArcSearchPoint> search_points(arcs.size());
  std::vector<std::array<float, 2>> attributes(arcs.size());
  {
    std::size_t i = 0;
    for (const BuiltModel& model : models) {
      for (std::size_t a = 0; a < model.arcs.size(); ++a, ++i) {
        if (model.arc_attributes.size() == model.arcs.size()) {
          attributes[i] = model.arc_attributes[a];
        } else {  // zero when a scale is unknown
          arc_attributes(keypoints[arcs[i].from], keypoints[arcs[i].to],
                         keypoint_scales[arcs[i].from], keypoint_scales[arcs[i].to],
                         attributes[i].data());
        }
      }
    }
  }
  for (std::size_t i = 0; i < arcs.size(); ++i)
    search_points[i] = search_point(descriptors[i], attributes[i].data());
  // Attributes are split as often as descriptor components when their box
  // is as wide, in the stored domain, as the similarity radius; never when
  // the box is off.
  const double box = attribute_box(params.graph);  // grid steps, in every encoding
  const double radius = static_cast<double>(params.descriptor.similarity_threshold) *
                        encoding_scale(params.descriptor.encoding);
  const double attribute_weight = box > 0.0 ? 0.5 * radius / box : 0.0;
  // Search tree in the parameters' encoding; arcs permuted into tree order.
  const DescriptorEncoding encoding = params.descriptor.encoding;
  std::vector<std::uint8_t> tree_points, tree_nodes, leaf_bounds;
  switch (encoding) {
    case DescriptorEncoding::kFloat32:
      encode_tree<float>(search_points, attribute_weight, arcs, tree_points, tree_nodes,
                         leaf_bounds);
      break;
    case DescriptorEncoding::kInt16:
      encode_tree<std::int16_t>(search_points, attribute_weight, arcs, tree_points, tree_nodes,
                                leaf_bounds);
      break;
    case DescriptorEncoding::kInt8:
      encode_tree<std::int8_t>(search_points, attribute_weight, arcs, tree_points, tree_nodes,
                               leaf_bounds);
      break;
  }
  const auto encoding_id = static_cast<std::uint32_t>(encoding);

  struct Payload {
    std::uint32_t id;
    std::uint32_t encoding;
    const void* data;
    std::size_t size;
    std::uint32_t count;
  };
  const auto arc_count = static_cast<std::uint32_t>(arcs.size());
  // Arcs as two aligned arrays: sources, and targets as int16 offsets (a
  // model's keypoints are at most kMaxModelKeypoints apart in id).
  std::vector<std::uint32_t> arc_from(arcs.size());
  std::vector<std::int16_t> arc_to_offset(arcs.size());
  for (std::size_t i = 0; i < arcs.size(); ++i) {
    const std::int64_t offset =
        static_cast<std::int64_t>(arcs[i].to) - static_cast<std::int64_t>(arcs[i].from);
    if (offset < -32768 || offset > 32767)
      return {StatusCode::kInvalidArgument, "a model has more than 32768 keypoints"};
    arc_from[i] = arcs[i].from;
    arc_to_offset[i] = static_cast<std::int16_t>(offset);
  }
  const Payload payloads[kLastSectionId] = {
      {kSectionModels, 0, records.data(), records.size(),
       static_cast<std::uint32_t>(models.size())},
      {kSectionStrings, 0, strings.data(), strings.size(),
       static_cast<std::uint32_t>(strings.size())},
      {kSectionKeypoints, 0, keypoints.data(), keypoints.size() * sizeof(Point2f),
       static_cast<std::uint32_t>(keypoints.size())},
      {kSectionTreeArcs, 0, arc_from.data(), arc_from.size() * sizeof(std::uint32_t), arc_count},
      {kSectionDescriptors, encoding_id, tree_points.data(), tree_points.size(), arc_count},
      {kSectionTreeNodes, encoding_id, tree_nodes.data(), tree_nodes.size(),
       static_cast<std::uint32_t>(tree_nodes.size() / tree_node_size(encoding))},
      {kSectionVertexDescriptors, 0, vertex_descriptors.data(), vertex_descriptors.size(),
       static_cast<std::uint32_t>(vertex_descriptors.size() / kVertexDescriptorSize)},
      {kSectionKeypointScales, 0, keypoint_scales.data(), keypoint_scales.size() * sizeof(float),
       static_cast<std::uint32_t>(keypoint_scales.size())},
      {kSectionTreeArcTargets, 0, arc_to_offset.data(), arc_to_offset.size() * sizeof(std::int16_t),
       arc_count},
      {kSectionLeafBounds, encoding_id, leaf_bounds.data(), leaf_bounds.size(),
       static_cast<std::uint32_t>(leaf_bounds.size() / encoded_point_size(encoding))},
      {kSectionKeypointViews, 0, keypoint_views.data(), keypoint_views.size(),
       static_cast<std::uint32_t>(keypoint_views.size() / 2)},
      {kSectionModelQuality, 0, quality_bytes.data(), quality_bytes.size(),
       static_cast<std::uint32_t>(quality_bytes.size() / kModelQualitySize)},
      {kSectionViewQuality, 0, view_quality_bytes.data(), view_quality_bytes.size(),
       static_cast<std::uint32_t>(view_quality_bytes.size() / kViewQualitySize)},
      {kSectionLookAlikes, 0, look_alike_bytes.data(), look_alike_bytes.size(),
       static_cast<std::uint32_t>(look_alike_bytes.size() / kLookAlikeSize)},
      {kSectionAppearances, 0, appearance_bytes.data(), appearance_bytes.size(),
       static_cast<std::uint32_t>(appearance_bytes.size() / kAppearanceSize)},
      {kSectionAppearancePixels, 0, appearance_pixels.data(), appearance_pixels.size(),
       static_cast<std::uint32_t>(appearance_pixels.size())},
  };
  const std::size_t params_offset = kHeaderSize;
  const std::size_t table_offset = params_offset + kParamsSize;
  const std::size_t table_end = table_offset + kLastSectionId * kSectionEntrySize;
  std::size_t offset = align_up(table_end);
  std::size_t offsets[kLastSectionId];
  for (std::uint32_t i = 0; i < kLastSectionId; ++i) {
    offsets[i] = offset;
    offset = align_up(offset + payloads[i].size);
  }
  bytes.assign(offset, 0);
  std::uint8_t* d = bytes.data();
  std::copy(std::begin(kMagic), std::end(kMagic), d + kOffMagic);
  store<std::uint16_t>(d + kOffMajor, kVersionMajor);
  store<std::uint16_t>(d + kOffMinor, kVersionMinor);
  store<std::uint32_t>(d + kOffHeaderSize, static_cast<std::uint32_t>(kHeaderSize));
  store<std::uint64_t>(d + kOffFileSize, static_cast<std::uint64_t>(bytes.size()));
  store<std::uint32_t>(d + kOffParamsOffset, static_cast<std::uint32_t>(params_offset));
  store<std::uint32_t>(d + kOffParamsSize, static_cast<std::uint32_t>(kParamsSize));
  store<std::uint32_t>(d + kOffTableOffset, static_cast<std::uint32_t>(table_offset));
  store<std::uint32_t>(d + kOffSectionCount, kLastSectionId);
  serialize_params(params, d + params_offset);
  for (std::uint32_t i = 0; i < kLastSectionId; ++i) {
    const Payload& p = payloads[i];
    if (p.size > 0) std::memcpy(d + offsets[i], p.data, p.size);
    std::uint8_t* e = d + table_offset + i * kSectionEntrySize;
    store<std::uint32_t>(e + kEntId, p.id);
    store<std::uint32_t>(e + kEntEncoding, p.encoding);
    store<std::uint64_t>(e + kEntOffset, offsets[i]);
    store<std::uint64_t>(e + kEntSize, p.size);
    store<std::uint32_t>(e + kEntCount, p.count);
    store<std::uint32_t>(e + kEntCrc, crc32(d + offsets[i], p.size));
  }
  store<std::uint32_t>(d + kOffHeaderCrc, crc32(d, table_end));
  return Status::ok();
}

Status write_index(const std::vector<BuiltModel>& models, const Params& params,
                   const std::string& path, const QualityReport* quality) {
  platform::OutputFile out;
  if (Status s = out.create(path); !s) return s;
  return write_index(models, params, out, quality);
}

Status write_index(const std::vector<BuiltModel>& models, const Params& params,
                   platform::OutputFile& out, const QualityReport* quality) {
  std::vector<std::uint8_t> bytes;
  Status s = serialize_index(models, params, bytes, quality);
  if (s) s = out.write(bytes.data(), bytes.size());
  if (s) s = out.commit();
  if (!s) out.discard();
  return s;
}

}  // namespace kg
