#include "keygraph/model_index.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <new>
#include <string>

#include <sys/stat.h>

#include "core/crc32.h"
#include "core/index_format.h"
#include "core/kdtree.h"

namespace kg {

using namespace format;

namespace {

Status corrupt(const std::string& what) {
  return {StatusCode::kCorruptData, what};
}

struct Section {
  std::uint32_t encoding = 0;
  std::uint64_t offset = 0;
  std::uint64_t size = 0;
  std::uint32_t count = 0;
  std::uint32_t crc = 0;
  bool present = false;
};

const char* section_name(std::uint32_t id) {
  switch (id) {
    case kSectionModels:
      return "models";
    case kSectionStrings:
      return "strings";
    case kSectionKeypoints:
      return "keypoints";
    case kSectionArcs:
      return "arcs";
    case kSectionDescriptors:
      return "descriptors";
    case kSectionTreeIds:
      return "tree ids";
    case kSectionTreeNodes:
      return "tree nodes";
    case kSectionVertexDescriptors:
      return "vertex descriptors";
    default:
      return "unknown";
  }
}

bool host_is_little_endian() {
  const std::uint16_t one = 1;
  std::uint8_t first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

}  // namespace

void ModelIndex::AlignedFree::operator()(std::uint8_t* p) const {
  ::operator delete[](p, std::align_val_t(kAlignment));
}

ModelIndex::ModelIndex() = default;
ModelIndex::~ModelIndex() = default;
ModelIndex::ModelIndex(ModelIndex&&) noexcept = default;
ModelIndex& ModelIndex::operator=(ModelIndex&&) noexcept = default;

Status ModelIndex::open(const std::string& path, ModelIndex& out) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) return {StatusCode::kNotFound, "cannot open index " + path};
  if (!S_ISREG(info.st_mode)) return {StatusCode::kInvalidArgument, path + ": not a regular file"};
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return {StatusCode::kNotFound, "cannot open index " + path};
  std::fseek(f, 0, SEEK_END);
  const long end = std::ftell(f);
  std::fseek(f, 0, SEEK_SET);
  if (end < 0) {
    std::fclose(f);
    return {StatusCode::kIoError, "cannot read index " + path};
  }
  const auto size = static_cast<std::size_t>(end);
  if (size < kHeaderSize) {
    std::fclose(f);
    return corrupt(path + ": file too small for a keygraph index (" + std::to_string(size) +
                   " bytes)");
  }
  std::unique_ptr<std::uint8_t, AlignedFree> buffer(static_cast<std::uint8_t*>(
      ::operator new[](size, std::align_val_t(kAlignment), std::nothrow)));
  if (!buffer) {
    std::fclose(f);
    return {StatusCode::kResourceExhausted, path + ": not enough memory for the index"};
  }
  const std::size_t got = std::fread(buffer.get(), 1, size, f);
  std::fclose(f);
  if (got != size) return {StatusCode::kIoError, "short read on index " + path};
  ModelIndex index;
  Status s = index.validate(buffer.get(), size);
  if (!s) return {s.code(), path + ": " + s.message()};
  index.owned_ = std::move(buffer);
  out = std::move(index);
  return Status::ok();
}

Status ModelIndex::view(const std::uint8_t* data, std::size_t size, ModelIndex& out) {
  if (data == nullptr) return {StatusCode::kInvalidArgument, "null index buffer"};
  if (reinterpret_cast<std::uintptr_t>(data) % kAlignment != 0)
    return {StatusCode::kInvalidArgument, "index buffer must be 64-byte aligned"};
  ModelIndex index;
  Status s = index.validate(data, size);
  if (!s) return s;
  out = std::move(index);
  return Status::ok();
}

Status ModelIndex::validate(const std::uint8_t* d, std::size_t size) {
  if (!host_is_little_endian()) return {StatusCode::kUnsupportedVersion, "big-endian host"};
  if (size < kHeaderSize) return corrupt("file too small for a keygraph index");
  if (std::memcmp(d + kOffMagic, kMagic, sizeof(kMagic)) != 0) {
    if (std::memcmp(d + 1, "KGI", 3) == 0)
      return corrupt("bad magic number (file damaged by a text-mode transfer?)");
    return corrupt("not a keygraph index (bad magic number)");
  }
  const auto major = load<std::uint16_t>(d + kOffMajor);
  const auto minor = load<std::uint16_t>(d + kOffMinor);
  if (major != kVersionMajor)
    return {StatusCode::kUnsupportedVersion,
            "index format version " + std::to_string(major) + "." + std::to_string(minor) +
                " is not supported (this reader reads " + std::to_string(kVersionMajor) + ".x)"};
  const auto header_size = load<std::uint32_t>(d + kOffHeaderSize);
  const auto file_size = load<std::uint64_t>(d + kOffFileSize);
  if (header_size != kHeaderSize)
    return corrupt("header: size field is " + std::to_string(header_size));
  if (file_size != size)
    return corrupt("header: file size field says " + std::to_string(file_size) +
                   " bytes, file has " + std::to_string(size) + " (truncated or padded)");
  const auto params_offset = load<std::uint32_t>(d + kOffParamsOffset);
  const auto params_size = load<std::uint32_t>(d + kOffParamsSize);
  const auto table_offset = load<std::uint32_t>(d + kOffTableOffset);
  const auto section_count = load<std::uint32_t>(d + kOffSectionCount);
  if (params_offset < kHeaderSize || params_size < kParamsSize || params_size > 4096 ||
      static_cast<std::uint64_t>(params_offset) + params_size > size)
    return corrupt("header: parameter block out of bounds");
  if (section_count == 0 || section_count > 64) return corrupt("header: bad section count");
  const std::uint64_t table_end = static_cast<std::uint64_t>(table_offset) +
                                  static_cast<std::uint64_t>(section_count) * kSectionEntrySize;
  if (table_offset < static_cast<std::uint64_t>(params_offset) + params_size || table_end > size)
    return corrupt("header: section table out of bounds");
  // Header checksum covers header, parameters and table with its own field zeroed.
  std::uint8_t zero[4] = {0, 0, 0, 0};
  std::uint32_t crc = crc32(d, kOffHeaderCrc);
  crc = crc32(zero, 4, crc);
  crc = crc32(d + kOffHeaderCrc + 4, static_cast<std::size_t>(table_end) - kOffHeaderCrc - 4, crc);
  if (crc != load<std::uint32_t>(d + kOffHeaderCrc)) return corrupt("header: checksum mismatch");

  Status s = parse_params(d + params_offset, params_size, params_);
  if (!s) return s;

  Section sections[kLastSectionId + 1];
  for (std::uint32_t i = 0; i < section_count; ++i) {
    const std::uint8_t* e = d + table_offset + static_cast<std::size_t>(i) * kSectionEntrySize;
    const auto id = load<std::uint32_t>(e + kEntId);
    if (id == 0 || id > kLastSectionId) continue;  // unknown sections: newer minor versions
    Section& sec = sections[id];
    const std::string name = section_name(id);
    if (sec.present) return corrupt("section table: duplicate " + name + " section");
    sec.present = true;
    sec.encoding = load<std::uint32_t>(e + kEntEncoding);
    sec.offset = load<std::uint64_t>(e + kEntOffset);
    sec.size = load<std::uint64_t>(e + kEntSize);
    sec.count = load<std::uint32_t>(e + kEntCount);
    sec.crc = load<std::uint32_t>(e + kEntCrc);
    if (sec.offset % kAlignment != 0) return corrupt(name + " section: offset not 64-byte aligned");
    if (sec.offset < table_end || sec.offset > size || sec.size > size - sec.offset)
      return corrupt(name + " section: offset " + std::to_string(sec.offset) + " size " +
                     std::to_string(sec.size) + " out of bounds");
    if (crc32(d + sec.offset, static_cast<std::size_t>(sec.size)) != sec.crc)
      return corrupt(name + " section: checksum mismatch");
  }
  for (std::uint32_t id = 1; id <= kSectionCount; ++id) {
    if (!sections[id].present) return corrupt(std::string(section_name(id)) + " section missing");
  }
  auto expect_size = [&](std::uint32_t id, std::uint64_t element) -> Status {
    const Section& sec = sections[id];
    if (sec.size != static_cast<std::uint64_t>(sec.count) * element)
      return corrupt(std::string(section_name(id)) + " section: size " + std::to_string(sec.size) +
                     " does not match count " + std::to_string(sec.count));
    return Status::ok();
  };
  const Section& models = sections[kSectionModels];
  const Section& strings = sections[kSectionStrings];
  const Section& keypoints = sections[kSectionKeypoints];
  const Section& arcs = sections[kSectionArcs];
  const Section& descriptors = sections[kSectionDescriptors];
  const Section& ids = sections[kSectionTreeIds];
  const Section& nodes = sections[kSectionTreeNodes];
  const Section& vertex = sections[kSectionVertexDescriptors];  // absent (1.0): empty
  if (!(s = expect_size(kSectionModels, kModelRecordSize))) return s;
  if (!(s = expect_size(kSectionKeypoints, sizeof(Point2f)))) return s;
  if (!(s = expect_size(kSectionArcs, sizeof(ModelArc)))) return s;
  if (descriptors.encoding != kFloat32)
    return corrupt("descriptors section: unknown encoding " + std::to_string(descriptors.encoding));
  if (!(s = expect_size(kSectionDescriptors, sizeof(ArcDescriptor)))) return s;
  if (!(s = expect_size(kSectionTreeIds, sizeof(std::uint32_t)))) return s;
  if (!(s = expect_size(kSectionTreeNodes, sizeof(KdNode)))) return s;
  if (!(s = expect_size(kSectionVertexDescriptors, kVertexDescriptorSize))) return s;
  if (strings.size != strings.count) return corrupt("strings section: size does not match count");
  if (models.count == 0) return corrupt("models section: no models");
  // One vertex descriptor per keypoint exactly when the parameters ask for them.
  const bool want_vertex = params_.descriptor.vertex_descriptor != VertexDescriptor::kNone;
  if (vertex.count != (want_vertex ? keypoints.count : 0U))
    return corrupt("vertex descriptors section: count " + std::to_string(vertex.count) +
                   ", expected " + std::to_string(want_vertex ? keypoints.count : 0U) +
                   (want_vertex ? " (one per keypoint: parameter vertex_descriptor is sift)"
                                : " (parameter vertex_descriptor is none)"));
  if (descriptors.count != arcs.count || ids.count != arcs.count)
    return corrupt("tree sections: slot count differs from arc count " +
                   std::to_string(arcs.count));
  const int depth = kdtree_depth(arcs.count);
  if (nodes.count != (1ULL << depth) - 1)
    return corrupt("tree nodes section: " + std::to_string(nodes.count) + " nodes, expected " +
                   std::to_string((1ULL << depth) - 1) + " for " + std::to_string(arcs.count) +
                   " arcs");

  // Model records: names, ranges, outlines.
  const std::uint8_t* rec = d + models.offset;
  std::uint32_t next_keypoint = 0, next_arc = 0;
  for (std::uint32_t m = 0; m < models.count; ++m, rec += kModelRecordSize) {
    const std::string where = "model " + std::to_string(m) + ": ";
    const auto name_offset = load<std::uint32_t>(rec + kModNameOffset);
    const auto name_length = load<std::uint32_t>(rec + kModNameLength);
    if (name_length == 0 || name_offset > strings.count ||
        name_length > strings.count - name_offset)
      return corrupt(where + "name out of bounds");
    const float w = load<float>(rec + kModWidth), h = load<float>(rec + kModHeight);
    if (!(w >= 1.f && h >= 1.f && w < 1e6f && h < 1e6f)) return corrupt(where + "bad image size");
    for (int c = 0; c < 8; ++c) {
      if (!std::isfinite(load<float>(rec + kModOutline + 4 * c)))
        return corrupt(where + "bad outline");
    }
    // Models own consecutive, non-overlapping keypoint and arc ranges.
    if (load<std::uint32_t>(rec + kModKeypointBegin) != next_keypoint ||
        load<std::uint32_t>(rec + kModArcBegin) != next_arc)
      return corrupt(where + "keypoint or arc range not contiguous");
    const auto kp_count = load<std::uint32_t>(rec + kModKeypointCount);
    const auto arc_count = load<std::uint32_t>(rec + kModArcCount);
    if (kp_count > keypoints.count - next_keypoint || arc_count > arcs.count - next_arc)
      return corrupt(where + "keypoint or arc range out of bounds");
    next_keypoint += kp_count;
    next_arc += arc_count;
  }
  if (next_keypoint != keypoints.count || next_arc != arcs.count)
    return corrupt("models section: ranges do not cover all keypoints and arcs");

  const auto* kp = reinterpret_cast<const Point2f*>(d + keypoints.offset);
  for (std::uint32_t i = 0; i < keypoints.count; ++i) {
    if (!std::isfinite(kp[i].x) || !std::isfinite(kp[i].y))
      return corrupt("keypoint " + std::to_string(i) + ": not finite");
  }
  // Every arc joins two distinct keypoints of the model that owns the arc.
  const auto* arc = reinterpret_cast<const ModelArc*>(d + arcs.offset);
  rec = d + models.offset;
  for (std::uint32_t m = 0; m < models.count; ++m, rec += kModelRecordSize) {
    const auto kb = load<std::uint32_t>(rec + kModKeypointBegin);
    const auto ke = kb + load<std::uint32_t>(rec + kModKeypointCount);
    const auto ab = load<std::uint32_t>(rec + kModArcBegin);
    const auto ae = ab + load<std::uint32_t>(rec + kModArcCount);
    for (std::uint32_t a = ab; a < ae; ++a) {
      if (arc[a].from < kb || arc[a].from >= ke || arc[a].to < kb || arc[a].to >= ke ||
          arc[a].from == arc[a].to)
        return corrupt("arc " + std::to_string(a) + ": keypoint ids outside model " +
                       std::to_string(m));
    }
  }
  const auto* desc = reinterpret_cast<const ArcDescriptor*>(d + descriptors.offset);
  for (std::uint32_t i = 0; i < descriptors.count; ++i) {
    for (float v : desc[i]) {
      if (!std::isfinite(v)) return corrupt("descriptor " + std::to_string(i) + ": not finite");
    }
  }
  const auto* slot_ids = reinterpret_cast<const std::uint32_t*>(d + ids.offset);
  for (std::uint32_t i = 0; i < ids.count; ++i) {
    if (slot_ids[i] >= arcs.count)
      return corrupt("tree ids: slot " + std::to_string(i) + " names arc " +
                     std::to_string(slot_ids[i]) + " of " + std::to_string(arcs.count));
  }
  const auto* tree_nodes = reinterpret_cast<const KdNode*>(d + nodes.offset);
  for (std::uint32_t i = 0; i < nodes.count; ++i) {
    if (tree_nodes[i].dim >= static_cast<std::uint32_t>(kDescriptorSize) ||
        !std::isfinite(tree_nodes[i].split))
      return corrupt("tree nodes: node " + std::to_string(i) + " has a bad split");
  }

  data_ = d;
  size_ = size;
  version_major_ = major;
  version_minor_ = minor;
  models_ = d + models.offset;
  model_count_ = models.count;
  strings_ = reinterpret_cast<const char*>(d + strings.offset);
  strings_size_ = strings.count;
  keypoints_ = kp;
  keypoint_count_ = keypoints.count;
  arcs_ = arc;
  arc_count_ = arcs.count;
  tree_points_ = desc;
  tree_ids_ = slot_ids;
  tree_nodes_ = tree_nodes;
  tree_depth_ = depth;
  vertex_descriptors_ = vertex.count > 0 ? d + vertex.offset : nullptr;
  return Status::ok();
}

ModelInfo ModelIndex::model(int i) const {
  ModelInfo info;
  if (i < 0 || static_cast<std::uint32_t>(i) >= model_count_) return info;
  const std::uint8_t* rec = models_ + static_cast<std::size_t>(i) * kModelRecordSize;
  info.name = std::string_view(strings_ + load<std::uint32_t>(rec + kModNameOffset),
                               load<std::uint32_t>(rec + kModNameLength));
  info.width = load<float>(rec + kModWidth);
  info.height = load<float>(rec + kModHeight);
  for (int c = 0; c < 4; ++c) {
    info.outline[c].x = load<float>(rec + kModOutline + 8 * c);
    info.outline[c].y = load<float>(rec + kModOutline + 8 * c + 4);
  }
  info.keypoint_begin = load<std::uint32_t>(rec + kModKeypointBegin);
  info.keypoint_count = load<std::uint32_t>(rec + kModKeypointCount);
  info.arc_begin = load<std::uint32_t>(rec + kModArcBegin);
  info.arc_count = load<std::uint32_t>(rec + kModArcCount);
  info.keygraph_count = load<std::uint64_t>(rec + kModKeygraphCount);
  return info;
}

int ModelIndex::last_model_starting_at_or_before(std::size_t field, std::uint32_t id) const {
  // Ranges are contiguous and ordered (checked in validate()); the owner is
  // the last model whose range starts at or before id.
  int lo = 0, hi = static_cast<int>(model_count_) - 1;
  while (lo < hi) {
    const int mid = (lo + hi + 1) / 2;
    if (load<std::uint32_t>(models_ + static_cast<std::size_t>(mid) * kModelRecordSize + field) <=
        id) {
      lo = mid;
    } else {
      hi = mid - 1;
    }
  }
  return lo;
}

int ModelIndex::model_of_arc(std::uint32_t arc) const {
  return last_model_starting_at_or_before(kModArcBegin, arc);
}

int ModelIndex::model_of_keypoint(std::uint32_t keypoint) const {
  return last_model_starting_at_or_before(kModKeypointBegin, keypoint);
}

}  // namespace kg
