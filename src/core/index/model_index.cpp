#include "keygraph/model_index.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <new>
#include <string>

#include <sys/stat.h>

#if defined(__unix__) || defined(__APPLE__)
#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>
#define KG_HAVE_MMAP 1
#else
#define KG_HAVE_MMAP 0
#endif

#include "core/description/arc_types.h"
#include "core/description/descriptor_encoding.h"
#include "core/index/crc32.h"
#include "core/index/index_format.h"
#include "core/index/index_internals.h"
#include "core/index/kdtree.h"
#include "core/support/page_memory.h"

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

bool host_is_little_endian() {
  const std::uint16_t one = 1;
  std::uint8_t first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

Status read_error(const std::string& path) {
  return {StatusCode::kIoError, "cannot read index " + path};
}

Status too_small(const std::string& path, std::size_t size) {
  return corrupt(path + ": file too small for a keygraph index (" + std::to_string(size) +
                 " bytes)");
}

const char* not_a_file(mode_t mode) {
  if (S_ISDIR(mode)) return "is a directory";
  if (S_ISFIFO(mode)) return "is a FIFO";
  if (S_ISCHR(mode)) return "is a character device";
  if (S_ISBLK(mode)) return "is a block device";
  if (S_ISSOCK(mode)) return "is a socket";
  return "is not a regular file";
}

// Opens the index file without blocking (a FIFO would block open() for
// ever) and checks that it is a regular file of a plausible size.
Status open_index_file(const std::string& path, int& fd, std::uint64_t& size) {
  fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) {
    const int err = errno;
    const std::string what = "cannot open index " + path;
    if (err == ENOENT) return {StatusCode::kNotFound, what + ": no such file"};
    if (err == EACCES || err == EPERM) return {StatusCode::kIoError, what + ": permission denied"};
    if (err == ELOOP) return {StatusCode::kIoError, what + ": too many levels of symbolic links"};
    return {StatusCode::kIoError, what + ": " + std::strerror(err)};
  }
  struct stat info {};
  if (::fstat(fd, &info) != 0) {
    ::close(fd);
    return read_error(path);
  }
  if (!S_ISREG(info.st_mode)) {
    ::close(fd);
    return {StatusCode::kInvalidArgument, path + ": " + not_a_file(info.st_mode)};
  }
  size = static_cast<std::uint64_t>(info.st_size);
  if (size < kHeaderSize) {
    ::close(fd);
    return too_small(path, static_cast<std::size_t>(size));
  }
  if (size > static_cast<std::uint64_t>(PTRDIFF_MAX)) {
    ::close(fd);
    return {StatusCode::kResourceExhausted, path + ": too large to load"};
  }
  return Status::ok();
}

// Reads exactly `size` bytes and checks that the file ends there (one byte
// more means it grew since fstat).
bool read_exactly(int fd, std::uint8_t* out, std::size_t size) {
  std::size_t got = 0;
  while (got < size) {
    const ssize_t r = ::read(fd, out + got, size - got);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    got += static_cast<std::size_t>(r);
  }
  std::uint8_t extra;
  return ::read(fd, &extra, 1) == 0;
}

void close_file(int fd) {
  ::close(fd);
}

// Versions a damaged header is unlikely to name by chance: a few majors
// ahead of this reader, minors below 100.
constexpr std::uint16_t kPlausibleNewerMajors = 4;
constexpr std::uint16_t kPlausibleMinor = 99;

// Whether the header checksum (over header, parameters and section table,
// its own field zeroed) matches, with this version's layout. False when the
// table lies outside the file.
bool header_crc_matches(const std::uint8_t* d, std::size_t size) {
  const auto table_offset = load<std::uint32_t>(d + kOffTableOffset);
  const auto section_count = load<std::uint32_t>(d + kOffSectionCount);
  const std::uint64_t table_end = static_cast<std::uint64_t>(table_offset) +
                                  static_cast<std::uint64_t>(section_count) * kSectionEntrySize;
  if (table_end < kOffHeaderCrc + 4 || table_end > size) return false;
  std::uint8_t zero[4] = {0, 0, 0, 0};
  std::uint32_t crc = crc32(d, kOffHeaderCrc);
  crc = crc32(zero, 4, crc);
  crc = crc32(d + kOffHeaderCrc + 4, static_cast<std::size_t>(table_end) - kOffHeaderCrc - 4, crc);
  return crc == load<std::uint32_t>(d + kOffHeaderCrc);
}

}  // namespace

void ModelIndex::Release::operator()(std::uint8_t* p) const {
  switch (kind) {
    case Kind::kPages:
      release_pages(p, bytes);
      return;
    case Kind::kFileMapping:
#if KG_HAVE_MMAP
      ::munmap(p, bytes);
#endif
      return;
    case Kind::kHeap:
      break;
  }
  ::operator delete[](p, std::align_val_t(kAlignment));
}

ModelIndex::ModelIndex() = default;
ModelIndex::~ModelIndex() = default;
ModelIndex::ModelIndex(ModelIndex&&) noexcept = default;
ModelIndex& ModelIndex::operator=(ModelIndex&&) noexcept = default;

Status ModelIndex::adopt(std::unique_ptr<std::uint8_t, Release> memory, std::size_t size,
                         const std::string& path, ModelIndex& out) {
  ModelIndex index;
  Status s = index.validate(memory.get(), size);
  if (!s) return {s.code(), path + ": " + s.message()};
  index.owned_ = std::move(memory);
  out = std::move(index);
  return Status::ok();
}

Status ModelIndex::read(const std::string& path, ModelIndex& out) {
  int fd = -1;
  std::uint64_t size = 0;
  if (Status s = open_index_file(path, fd, size); !s) return s;
  // Pages rather than the heap: a process that reloads its index (keygraph
  // live) gives each copy back to the system whole (core/support/page_memory.h).
  std::unique_ptr<std::uint8_t, Release> buffer(
      static_cast<std::uint8_t*>(allocate_pages(static_cast<std::size_t>(size))),
      Release{static_cast<std::size_t>(size), Release::Kind::kPages});
  if (!buffer) {
    close_file(fd);
    return {StatusCode::kResourceExhausted, path + ": not enough memory for the index"};
  }
  const bool complete = read_exactly(fd, buffer.get(), static_cast<std::size_t>(size));
  close_file(fd);
  if (!complete) return read_error(path + " (file changed while reading)");
  return adopt(std::move(buffer), static_cast<std::size_t>(size), path, out);
}

Status ModelIndex::open(const std::string& path, ModelIndex& out) {
#if KG_HAVE_MMAP
  int fd = -1;
  std::uint64_t size = 0;
  if (Status s = open_index_file(path, fd, size); !s) return s;
  void* mapped = ::mmap(nullptr, static_cast<std::size_t>(size), PROT_READ, MAP_PRIVATE, fd, 0);
  ::close(fd);  // the mapping keeps the file
  if (mapped != MAP_FAILED) {
    std::unique_ptr<std::uint8_t, Release> memory(
        static_cast<std::uint8_t*>(mapped),
        Release{static_cast<std::size_t>(size), Release::Kind::kFileMapping});
    return adopt(std::move(memory), static_cast<std::size_t>(size), path, out);
  }
#endif
  // No mmap here, or it failed (file system without mapping support): copy.
  return read(path, out);
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
  // Error messages are built only on failure: a valid index loads without
  // allocating (beyond nothing at all).
  if (!host_is_little_endian()) return {StatusCode::kUnsupportedVersion, "big-endian host"};
  if (size < kHeaderSize) return corrupt("file too small for a keygraph index");
  if (std::memcmp(d + kOffMagic, kMagic, sizeof(kMagic)) != 0) {
    if (std::memcmp(d + 1, "KGI", 3) == 0)
      return corrupt("bad magic number (file damaged by a text-mode transfer?)");
    return corrupt("not a keygraph index (bad magic number)");
  }
  const auto major = load<std::uint16_t>(d + kOffMajor);
  const auto minor = load<std::uint16_t>(d + kOffMinor);
  // Another major version is named only when the header is believable: its
  // checksum holds (as far as this version's layout can tell) or the version
  // is one keygraph has written or may soon write. Random bytes after the
  // magic are damage, not "a newer keygraph".
  if (major != kVersionMajor && !header_crc_matches(d, size) &&
      (major == 0 || major > kVersionMajor + kPlausibleNewerMajors || minor > kPlausibleMinor)) {
    return corrupt("header: damaged (version field " + std::to_string(major) + "." +
                   std::to_string(minor) + " is not a keygraph version and the header checksum " +
                   "does not match)");
  }
  if (major != kVersionMajor) {
    const std::string version = "index format version " + std::to_string(major) + "." +
                                std::to_string(minor) + " is not supported (this reader reads " +
                                std::to_string(kVersionMajor) + ".x";
    if (major < kVersionMajor)
      return {StatusCode::kUnsupportedVersion,
              version + "): rebuild the index from its model images with keygraph build"};
    return {StatusCode::kUnsupportedVersion,
            version + "): it was written by a newer keygraph; update the reader"};
  }
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
  if (params_offset < kHeaderSize || params_size < kMinParamsSize || params_size > 4096 ||
      static_cast<std::uint64_t>(params_offset) + params_size > size)
    return corrupt("header: parameter block out of bounds");
  if (section_count == 0 || section_count > 64) return corrupt("header: bad section count");
  const std::uint64_t table_end = static_cast<std::uint64_t>(table_offset) +
                                  static_cast<std::uint64_t>(section_count) * kSectionEntrySize;
  if (table_offset < static_cast<std::uint64_t>(params_offset) + params_size || table_end > size)
    return corrupt("header: section table out of bounds");
  if (!header_crc_matches(d, size)) return corrupt("header: checksum mismatch");
  // Reserved bytes are zero: a later version that gives them a meaning is a
  // new major version (additions within one go into new sections and the
  // parameter block's tail), so a reader never misreads them.
  for (std::size_t i = kOffHeaderCrc + 4; i < kHeaderSize; ++i) {
    if (d[i] != 0) return corrupt("header: reserved byte " + std::to_string(i) + " is not zero");
  }

  Status s = parse_params(d + params_offset, params_size, params_);
  if (!s) return s;
  const DescriptorEncoding encoding = params_.descriptor.encoding;

  Section sections[kLastSectionId + 1];
  for (std::uint32_t i = 0; i < section_count; ++i) {
    const std::uint8_t* e = d + table_offset + static_cast<std::size_t>(i) * kSectionEntrySize;
    const auto id = load<std::uint32_t>(e + kEntId);
    if (id == 0 || id > kLastSectionId) continue;  // unknown sections: newer minor versions
    Section& sec = sections[id];
    const char* name = section_name(id);
    if (sec.present) return corrupt(std::string("section table: duplicate ") + name + " section");
    sec.present = true;
    sec.encoding = load<std::uint32_t>(e + kEntEncoding);
    sec.offset = load<std::uint64_t>(e + kEntOffset);
    sec.size = load<std::uint64_t>(e + kEntSize);
    sec.count = load<std::uint32_t>(e + kEntCount);
    sec.crc = load<std::uint32_t>(e + kEntCrc);
    if (sec.offset % kAlignment != 0)
      return corrupt(std::string(name) + " section: offset not 64-byte aligned");
    if (sec.offset < table_end || sec.offset > size || sec.size > size - sec.offset)
      return corrupt(std::string(name) + " section: offset " + std::to_string(sec.offset) +
                     " size " + std::to_string(sec.size) + " out of bounds");
    if (crc32(d + sec.offset, static_cast<std::size_t>(sec.size)) != sec.crc)
      return corrupt(std::string(name) + " section: checksum mismatch");
  }
  // The sections this reader reads do not overlap one another (each byte
  // has one meaning; empty sections take no bytes). Sorted by offset, in a
  // fixed array: no allocation.
  {
    std::uint32_t order[kLastSectionId + 1];
    std::uint32_t n = 0;
    for (std::uint32_t id = 1; id <= kLastSectionId; ++id) {
      if (sections[id].present && sections[id].size > 0) order[n++] = id;
    }
    std::sort(order, order + n, [&](std::uint32_t a, std::uint32_t b) {
      return sections[a].offset < sections[b].offset;
    });
    for (std::uint32_t i = 1; i < n; ++i) {
      const Section& before = sections[order[i - 1]];
      if (before.offset + before.size > sections[order[i]].offset)
        return corrupt(std::string(section_name(order[i])) + " section overlaps the " +
                       section_name(order[i - 1]) + " section");
    }
  }
  // Minor version 1 added the quality sections, 2 the appearance sections:
  // required from then on.
  const std::uint32_t required = last_required_section(minor);
  for (std::uint32_t id = 1; id <= required; ++id) {
    if (!sections[id].present) return corrupt(std::string(section_name(id)) + " section missing");
  }
  auto expect_size = [&](std::uint32_t id, std::uint64_t element) -> Status {
    const Section& sec = sections[id];
    if (sec.size != static_cast<std::uint64_t>(sec.count) * element)
      return corrupt(std::string(section_name(id)) + " section: size " + std::to_string(sec.size) +
                     " does not match count " + std::to_string(sec.count) + " x " +
                     std::to_string(element) + " bytes");
    return Status::ok();
  };
  const Section& models = sections[kSectionModels];
  const Section& strings = sections[kSectionStrings];
  const Section& keypoints = sections[kSectionKeypoints];
  const Section& arcs = sections[kSectionTreeArcs];
  const Section& targets = sections[kSectionTreeArcTargets];
  const Section& bounds = sections[kSectionLeafBounds];
  const Section& descriptors = sections[kSectionDescriptors];
  const Section& nodes = sections[kSectionTreeNodes];
  const Section& vertex = sections[kSectionVertexDescriptors];
  const Section& scales = sections[kSectionKeypointScales];
  const Section& views = sections[kSectionKeypointViews];
  // The point, node and bound sections name the encoding the parameters name.
  for (const std::uint32_t id : {kSectionDescriptors, kSectionTreeNodes, kSectionLeafBounds}) {
    if (sections[id].encoding != static_cast<std::uint32_t>(encoding))
      return corrupt(std::string(section_name(id)) + " section: encoding " +
                     std::to_string(sections[id].encoding) + " differs from parameter encoding " +
                     std::to_string(static_cast<unsigned>(encoding)) + " (" +
                     encoding_name(encoding) + ")");
  }
  if (!(s = expect_size(kSectionModels, kModelRecordSize))) return s;
  if (!(s = expect_size(kSectionStrings, 1))) return s;
  if (!(s = expect_size(kSectionKeypoints, sizeof(Point2f)))) return s;
  if (!(s = expect_size(kSectionTreeArcs, sizeof(std::uint32_t)))) return s;
  if (!(s = expect_size(kSectionTreeArcTargets, sizeof(std::int16_t)))) return s;
  if (targets.count != arcs.count)
    return corrupt("tree arc targets section: " + std::to_string(targets.count) + " targets for " +
                   std::to_string(arcs.count) + " tree arcs");
  if (!(s = expect_size(kSectionDescriptors, encoded_point_size(encoding)))) return s;
  if (!(s = expect_size(kSectionTreeNodes, tree_node_size(encoding)))) return s;
  if (!(s = expect_size(kSectionVertexDescriptors, kVertexDescriptorSize))) return s;
  if (!(s = expect_size(kSectionKeypointScales, sizeof(float)))) return s;
  if (scales.count != keypoints.count)
    return corrupt("keypoint scales section: count " + std::to_string(scales.count) +
                   ", expected " + std::to_string(keypoints.count) + " (one per keypoint)");
  if (!(s = expect_size(kSectionKeypointViews, 2))) return s;
  if (views.count != keypoints.count)
    return corrupt("keypoint views section: count " + std::to_string(views.count) + ", expected " +
                   std::to_string(keypoints.count) + " (one per keypoint)");
  if (models.count == 0) return corrupt("models section: no models");
  // One vertex descriptor per keypoint exactly when the parameters ask for them.
  const bool want_vertex = params_.descriptor.vertex_descriptor != VertexDescriptor::kNone;
  if (vertex.count != (want_vertex ? keypoints.count : 0U))
    return corrupt("vertex descriptors section: count " + std::to_string(vertex.count) +
                   ", expected " + std::to_string(want_vertex ? keypoints.count : 0U) +
                   (want_vertex ? " (one per keypoint: parameter vertex_descriptor is sift)"
                                : " (parameter vertex_descriptor is none)"));
  if (descriptors.count != arcs.count)
    return corrupt("descriptors section: " + std::to_string(descriptors.count) +
                   " descriptors for " + std::to_string(arcs.count) + " tree arcs");
  const int depth = kdtree_depth(arcs.count);
  if (!(s = expect_size(kSectionLeafBounds, encoded_point_size(encoding)))) return s;
  if (bounds.count != 2 * (1ULL << depth))
    return corrupt("leaf bounds section: " + std::to_string(bounds.count) + " points, expected " +
                   std::to_string(2 * (1ULL << depth)) + " (two per leaf)");
  if (nodes.count != (1ULL << depth) - 1)
    return corrupt("tree nodes section: " + std::to_string(nodes.count) + " nodes, expected " +
                   std::to_string((1ULL << depth) - 1) + " for " + std::to_string(arcs.count) +
                   " arcs");

  // Model records: names, ranges, outlines.
  const std::uint8_t* rec = d + models.offset;
  std::uint32_t next_keypoint = 0;
  std::uint64_t arc_total = 0;
  for (std::uint32_t m = 0; m < models.count; ++m, rec += kModelRecordSize) {
    auto model_error = [m](const char* what) {
      return corrupt("model " + std::to_string(m) + ": " + what);
    };
    const auto name_offset = load<std::uint32_t>(rec + kModNameOffset);
    const auto name_length = load<std::uint32_t>(rec + kModNameLength);
    if (name_length == 0 || name_offset > strings.count ||
        name_length > strings.count - name_offset)
      return model_error("name out of bounds");
    const float w = load<float>(rec + kModWidth), h = load<float>(rec + kModHeight);
    if (!(w >= 1.f && h >= 1.f && w < 1e6f && h < 1e6f)) return model_error("bad image size");
    // The outline lies on the model image: every corner within its extent
    // (pixel centres, -0.5 .. size - 0.5), so that a pose maps it to a
    // quadrilateral of the frame's scale (an outline of 1e30 would not).
    for (int c = 0; c < 8; ++c) {
      const float v = load<float>(rec + kModOutline + 4 * c);
      const float extent = c % 2 == 0 ? w : h;
      if (!(v >= -0.5f && v <= extent - 0.5f)) return model_error("bad outline");
    }
    if (load<std::uint32_t>(rec + kModReserved) != 0 ||
        load<std::uint64_t>(rec + kModOutline + 32) != 0)
      return model_error("reserved bytes are not zero");
    // Models own consecutive, non-overlapping keypoint ranges.
    if (load<std::uint32_t>(rec + kModKeypointBegin) != next_keypoint)
      return model_error("keypoint range not contiguous");
    const auto kp_count = load<std::uint32_t>(rec + kModKeypointCount);
    if (kp_count > keypoints.count - next_keypoint)
      return model_error("keypoint range out of bounds");
    next_keypoint += kp_count;
    arc_total += load<std::uint32_t>(rec + kModArcCount);
  }
  if (next_keypoint != keypoints.count)
    return corrupt("models section: keypoint ranges do not cover all keypoints");
  if (arc_total != arcs.count)
    return corrupt("models section: arc counts add up to " + std::to_string(arc_total) + ", not " +
                   std::to_string(arcs.count));

  const auto* kp = reinterpret_cast<const Point2f*>(d + keypoints.offset);
  for (std::uint32_t i = 0; i < keypoints.count; ++i) {
    if (!std::isfinite(kp[i].x) || !std::isfinite(kp[i].y))
      return corrupt("keypoint " + std::to_string(i) + ": not finite");
  }
  // Scales: finite and >= 0 (0: unknown, e.g. MSER centroids).
  const auto* kp_scales = reinterpret_cast<const float*>(d + scales.offset);
  for (std::uint32_t i = 0; i < keypoints.count; ++i) {
    if (!(std::isfinite(kp_scales[i]) && kp_scales[i] >= 0.f && kp_scales[i] < 1e6f))
      return corrupt("keypoint " + std::to_string(i) + ": scale not finite or negative");
  }
  // View scale codes: finest <= coarsest.
  const std::uint8_t* kp_views = d + views.offset;
  for (std::uint32_t i = 0; i < keypoints.count; ++i) {
    if (kp_views[2 * i] > kp_views[2 * i + 1])
      return corrupt("keypoint " + std::to_string(i) + ": view scale range reversed");
  }
  // These are needed by model_of_keypoint() below.
  models_ = d + models.offset;
  model_count_ = models.count;
  // Every arc joins two distinct keypoints of one model, and each model
  // record's arc count is the number of arcs starting in it. Counted in
  // chunks of models with a fixed array: no allocation.
  arc_from_ = reinterpret_cast<const std::uint32_t*>(d + arcs.offset);
  arc_to_offset_ = reinterpret_cast<const std::int16_t*>(d + targets.offset);
  constexpr std::uint32_t kChunk = 256;
  std::uint32_t per_model[kChunk];
  for (std::uint32_t first = 0; first < models.count; first += kChunk) {
    const std::uint32_t last = std::min(models.count, first + kChunk);
    std::fill(per_model, per_model + kChunk, 0U);
    for (std::uint32_t a = 0; a < arcs.count; ++a) {
      const std::int64_t from = arc_from_[a], to = from + arc_to_offset_[a];
      if (from >= keypoints.count || to < 0 || to >= keypoints.count || from == to)
        return corrupt("tree arc " + std::to_string(a) + ": keypoint ids " + std::to_string(from) +
                       ", " + std::to_string(to) + " invalid (" + std::to_string(keypoints.count) +
                       " keypoints)");
      const ModelArc x = arc(a);
      const auto m = static_cast<std::uint32_t>(model_of_keypoint(x.from));
      if (first == 0 && static_cast<std::uint32_t>(model_of_keypoint(x.to)) != m)
        return corrupt("tree arc " + std::to_string(a) + ": keypoint ids outside model " +
                       std::to_string(m));
      if (m >= first && m < last) ++per_model[m - first];
    }
    for (std::uint32_t m = first; m < last; ++m) {
      const auto stored = load<std::uint32_t>(models_ + m * kModelRecordSize + kModArcCount);
      if (stored != per_model[m - first])
        return corrupt("model " + std::to_string(m) + ": arc count " + std::to_string(stored) +
                       ", but " + std::to_string(per_model[m - first]) + " arcs start in it");
    }
  }
  // Descriptors: finite (float32) or within [-scale, scale] (int16, int8),
  // so integer squared distances cannot overflow.
  const std::uint8_t* desc = d + descriptors.offset;
  const std::uint8_t* node = d + nodes.offset;
  const std::int32_t scale = encoding_scale(encoding);
  auto bad_descriptor = [](std::uint32_t i) {
    return corrupt("descriptor " + std::to_string(i) + ": not finite or out of range");
  };
  auto bad_node = [](std::uint32_t i) {
    return corrupt("tree nodes: node " + std::to_string(i) + " has a bad split");
  };
  switch (encoding) {
    case DescriptorEncoding::kFloat32: {
      const auto* p = reinterpret_cast<const ArcSearchPoint*>(desc);
      for (std::uint32_t i = 0; i < descriptors.count; ++i) {
        for (float v : p[i]) {
          if (!std::isfinite(v)) return bad_descriptor(i);
        }
      }
      const auto* n = reinterpret_cast<const KdNode*>(node);
      for (std::uint32_t i = 0; i < nodes.count; ++i) {
        if (n[i].dim >= static_cast<std::uint32_t>(kSearchDims) || !std::isfinite(n[i].split))
          return bad_node(i);
      }
      break;
    }
    case DescriptorEncoding::kInt16: {
      const auto* p = reinterpret_cast<const ArcSearchPointI16*>(desc);
      for (std::uint32_t i = 0; i < descriptors.count; ++i) {
        for (std::int16_t v : p[i]) {
          if (v < -scale) return bad_descriptor(i);  // -32768
        }
      }
      break;
    }
    case DescriptorEncoding::kInt8: {
      const auto* p = reinterpret_cast<const ArcSearchPointI8*>(desc);
      for (std::uint32_t i = 0; i < descriptors.count; ++i) {
        for (std::int8_t v : p[i]) {
          if (v < -scale) return bad_descriptor(i);  // -128
        }
      }
      break;
    }
  }
  if (encoding != DescriptorEncoding::kFloat32) {
    const auto* n = reinterpret_cast<const KdNodeInt*>(node);
    for (std::uint32_t i = 0; i < nodes.count; ++i) {
      if (n[i].dim >= kSearchDims || n[i].split < -scale || n[i].split > scale) return bad_node(i);
    }
  }

  if (sections[kSectionModelQuality].present) {
    const Section& quality = sections[kSectionModelQuality];
    const Section& view_quality = sections[kSectionViewQuality];
    const Section& look_alikes = sections[kSectionLookAlikes];
    if (!view_quality.present || !look_alikes.present)
      return corrupt("model quality section without the view quality and look-alikes sections");
    if (!(s = expect_size(kSectionModelQuality, kModelQualitySize))) return s;
    if (!(s = expect_size(kSectionViewQuality, kViewQualitySize))) return s;
    if (!(s = expect_size(kSectionLookAlikes, kLookAlikeSize))) return s;
    if (!(s = validate_quality(d + quality.offset, quality.count, d + view_quality.offset,
                               view_quality.count, d + look_alikes.offset, look_alikes.count)))
      return s;
    if (quality.count > 0) {
      model_quality_ = d + quality.offset;
      view_quality_ = d + view_quality.offset;
      view_quality_count_ = view_quality.count;
      look_alikes_ = d + look_alikes.offset;
      look_alike_count_ = look_alikes.count;
    }
  }

  // Appearances: one per model exactly when the parameters ask for them
  // (older files, without the sections, only when they do not).
  {
    const Section& records = sections[kSectionAppearances];
    const Section& pixels = sections[kSectionAppearancePixels];
    if (records.present != pixels.present)
      return corrupt("model appearance and appearance pixels sections: one without the other");
    if (records.present) {
      if (!(s = expect_size(kSectionAppearances, kAppearanceSize))) return s;
      if (!(s = expect_size(kSectionAppearancePixels, 1))) return s;
    }
    const std::uint32_t record_count = records.present ? records.count : 0;
    const std::uint32_t pixel_count = pixels.present ? pixels.count : 0;
    const std::uint32_t want = params_.views.appearance_size > 0 ? models.count : 0;
    if (record_count != want)
      return corrupt("model appearance section: count " + std::to_string(record_count) +
                     ", expected " + std::to_string(want) +
                     " (one per model when parameter views.appearance_size, here " +
                     std::to_string(params_.views.appearance_size) + ", is above 0)");
    int max_pixels = 0;
    if (!(s = validate_appearances(d + records.offset, record_count, pixel_count, max_pixels)))
      return s;
    if (record_count > 0) {
      appearances_ = d + records.offset;
      appearance_pixels_ = d + pixels.offset;
      max_appearance_pixels_ = max_pixels;
    }
  }

  data_ = d;
  size_ = size;
  version_major_ = major;
  version_minor_ = minor;
  strings_ = reinterpret_cast<const char*>(d + strings.offset);
  strings_size_ = strings.count;
  keypoints_ = kp;
  keypoint_count_ = keypoints.count;
  arc_count_ = arcs.count;
  tree_descriptors_ = desc;
  tree_nodes_ = node;
  tree_node_count_ = nodes.count;
  leaf_bounds_ = d + bounds.offset;
  tree_depth_ = depth;
  vertex_descriptors_ = vertex.count > 0 ? d + vertex.offset : nullptr;
  keypoint_scales_ = kp_scales;
  keypoint_views_ = kp_views;
  return Status::ok();
}

// The quality sections (12-14) against the models (validate() has checked
// the model records and their arc counts): one record per model or none at
// all, view ranges consecutive and covering section 13, values finite and in
// range, look-alike pairs of two distinct models, sorted and distinct.
Status ModelIndex::validate_quality(const std::uint8_t* quality, std::uint32_t quality_count,
                                    const std::uint8_t* views, std::uint32_t view_count,
                                    const std::uint8_t* pairs, std::uint32_t pair_count) const {
  if (quality_count == 0) {
    if (view_count != 0 || pair_count != 0)
      return corrupt("view quality and look-alikes sections: not empty without model quality");
    return Status::ok();
  }
  if (quality_count != model_count_)
    return corrupt("model quality section: count " + std::to_string(quality_count) + ", expected " +
                   std::to_string(model_count_) + " (one per model, or none)");
  std::uint32_t next_view = 0;
  for (std::uint32_t m = 0; m < quality_count; ++m) {
    const std::uint8_t* q = quality + static_cast<std::size_t>(m) * kModelQualitySize;
    auto bad = [m](const char* what) {
      return corrupt("model quality " + std::to_string(m) + ": " + what);
    };
    if (load<std::uint32_t>(q + kMqViewBegin) != next_view) return bad("view range not contiguous");
    const auto count = load<std::uint32_t>(q + kMqViewCount);
    if (count > view_count - next_view) return bad("view range out of bounds");
    next_view += count;
    const auto arcs = load<std::uint32_t>(models_ + m * kModelRecordSize + kModArcCount);
    if (load<std::uint32_t>(q + kMqSharedArcs) > arcs) return bad("more shared arcs than arcs");
    const float smallest = load<float>(q + kMqSmallestSize);
    const float scene = load<float>(q + kMqSceneSize);
    if (!(smallest >= 0.f && smallest < 1e6f) || !(scene >= 0.f && scene < 1e6f))
      return bad("bad size");
    const auto flags = load<std::uint32_t>(q + kMqFlags);
    if ((flags & ~kQualityFlagsKnown) != 0 || load<std::uint64_t>(q + kMqReserved) != 0)
      return bad("unknown flags or reserved bytes set");
  }
  if (next_view != view_count)
    return corrupt("model quality section: view ranges do not cover all view records");
  // Views larger than the model image reach views.max_scale (6.7; 1 before).
  const float largest_scale = params_.views.max_scale * 1.001f;
  for (std::uint32_t v = 0; v < view_count; ++v) {
    const std::uint8_t* r = views + static_cast<std::size_t>(v) * kViewQualitySize;
    const float scale = load<float>(r + kVqScale), tilt = load<float>(r + kVqTilt),
                longitude = load<float>(r + kVqLongitude);
    if (!(scale > 0.f && scale <= largest_scale) || !(tilt >= 1.f && tilt < 1e3f) ||
        !(longitude >= 0.f && longitude < 180.f))
      return corrupt("view quality " + std::to_string(v) + ": bad scale, tilt or longitude");
  }
  for (std::uint32_t i = 0; i < pair_count; ++i) {
    const std::uint8_t* p = pairs + static_cast<std::size_t>(i) * kLookAlikeSize;
    const auto shown = load<std::uint32_t>(p), detected = load<std::uint32_t>(p + 4);
    if (shown >= model_count_ || detected >= model_count_ || shown == detected)
      return corrupt("look-alike " + std::to_string(i) + ": model ids " + std::to_string(shown) +
                     ", " + std::to_string(detected) + " invalid");
    if (i > 0) {
      const auto prev_shown = load<std::uint32_t>(p - kLookAlikeSize);
      const auto prev_detected = load<std::uint32_t>(p - kLookAlikeSize + 4);
      if (prev_shown > shown || (prev_shown == shown && prev_detected >= detected))
        return corrupt("look-alike " + std::to_string(i) + ": pairs not sorted or repeated");
    }
  }
  return Status::ok();
}

// The appearance records (section 15) against the models and the pixel
// count of section 16: each size within views.appearance_size and what the
// model's size and the scale give, pixel ranges consecutive and covering
// the pixels. `max_pixels` gets the largest width * height.
Status ModelIndex::validate_appearances(const std::uint8_t* records, std::uint32_t record_count,
                                        std::uint64_t pixel_count, int& max_pixels) const {
  max_pixels = 0;
  const auto limit = static_cast<std::uint32_t>(params_.views.appearance_size);
  std::uint64_t next_pixel = 0;
  for (std::uint32_t m = 0; m < record_count; ++m) {
    const std::uint8_t* r = records + static_cast<std::size_t>(m) * kAppearanceSize;
    auto bad = [m](const std::string& what) {
      return corrupt("model appearance " + std::to_string(m) + ": " + what);
    };
    const auto width = load<std::uint32_t>(r + kApWidth);
    const auto height = load<std::uint32_t>(r + kApHeight);
    const float scale = load<float>(r + kApScale);
    if (width < 1 || height < 1 || width > limit || height > limit)
      return bad("size " + std::to_string(width) + "x" + std::to_string(height) +
                 " not within 1.." + std::to_string(limit) + " (views.appearance_size)");
    if (!(scale > 0.f && scale <= 1.f)) return bad("scale not in (0, 1]");
    // The model's size at that scale, to the pixel; downsampled only as far
    // as the appearance size.
    const std::uint8_t* model = models_ + static_cast<std::size_t>(m) * kModelRecordSize;
    const double model_width = load<float>(model + kModWidth);
    const double model_height = load<float>(model + kModHeight);
    if (std::fabs(width - model_width * scale) > 1.0 ||
        std::fabs(height - model_height * scale) > 1.0)
      return bad("size " + std::to_string(width) + "x" + std::to_string(height) +
                 " is not the model's size times the scale");
    if (scale < 1.f && std::max(width, height) != limit)
      return bad("downsampled, but its long edge is not views.appearance_size");
    if (load<std::uint32_t>(r + kApFirstPixel) != next_pixel)
      return bad("pixel range not contiguous");
    const std::uint64_t pixels = std::uint64_t{width} * height;  // <= 512 x 512
    if (pixels > pixel_count - next_pixel) return bad("pixel range out of bounds");
    next_pixel += pixels;
    max_pixels = std::max(max_pixels, static_cast<int>(pixels));
  }
  if (next_pixel != pixel_count)
    return corrupt("appearance pixels section: " + std::to_string(pixel_count) +
                   " pixels, the appearances cover " + std::to_string(next_pixel));
  return Status::ok();
}

ModelAppearance ModelIndex::appearance(int model) const {
  ModelAppearance a;
  if (appearances_ == nullptr || model < 0 || static_cast<std::uint32_t>(model) >= model_count_)
    return a;
  const std::uint8_t* r = appearances_ + static_cast<std::size_t>(model) * kAppearanceSize;
  a.pixels = appearance_pixels_ + load<std::uint32_t>(r + kApFirstPixel);
  a.width = static_cast<int>(load<std::uint32_t>(r + kApWidth));
  a.height = static_cast<int>(load<std::uint32_t>(r + kApHeight));
  a.scale = load<float>(r + kApScale);
  return a;
}

ModelQuality ModelIndex::model_quality(int i) const {
  ModelQuality q;
  if (model_quality_ == nullptr || i < 0 || static_cast<std::uint32_t>(i) >= model_count_) return q;
  const std::uint8_t* r = model_quality_ + static_cast<std::size_t>(i) * kModelQualitySize;
  q.view_begin = load<std::uint32_t>(r + kMqViewBegin);
  q.view_count = load<std::uint32_t>(r + kMqViewCount);
  q.shared_arcs = load<std::uint32_t>(r + kMqSharedArcs);
  q.smallest_size = load<float>(r + kMqSmallestSize);
  q.scene_size = load<float>(r + kMqSceneSize);
  q.found_in_scene = (load<std::uint32_t>(r + kMqFlags) & kQualityFoundInScene) != 0;
  return q;
}

ViewQuality ModelIndex::view_quality(std::uint32_t i) const {
  ViewQuality v;
  if (i >= view_quality_count_) return v;
  const std::uint8_t* r = view_quality_ + static_cast<std::size_t>(i) * kViewQualitySize;
  v.scale = load<float>(r + kVqScale);
  v.tilt = load<float>(r + kVqTilt);
  v.longitude = load<float>(r + kVqLongitude);
  v.keypoints = load<std::uint32_t>(r + kVqKeypoints);
  v.arcs = load<std::uint32_t>(r + kVqArcs);
  v.keygraphs = load<std::uint32_t>(r + kVqKeygraphs);
  return v;
}

LookAlike ModelIndex::look_alike(std::uint32_t i) const {
  if (i >= look_alike_count_) return {};
  const std::uint8_t* r = look_alikes_ + static_cast<std::size_t>(i) * kLookAlikeSize;
  return {load<std::uint32_t>(r), load<std::uint32_t>(r + 4)};
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
  info.arc_count = load<std::uint32_t>(rec + kModArcCount);
  info.keygraph_count = load<std::uint64_t>(rec + kModKeygraphCount);
  return info;
}

int ModelIndex::model_of_keypoint(std::uint32_t keypoint) const {
  // Ranges are contiguous and ordered (checked in validate()); the owner is
  // the last model whose range starts at or before the keypoint.
  int lo = 0, hi = static_cast<int>(model_count_) - 1;
  while (lo < hi) {
    const int mid = (lo + hi + 1) / 2;
    if (load<std::uint32_t>(models_ + static_cast<std::size_t>(mid) * kModelRecordSize +
                            kModKeypointBegin) <= keypoint) {
      lo = mid;
    } else {
      hi = mid - 1;
    }
  }
  return lo;
}

const ArcSearchPoint* IndexInternals::tree_points_f32(const ModelIndex& index) {
  return index.descriptor_encoding() == DescriptorEncoding::kFloat32
             ? reinterpret_cast<const ArcSearchPoint*>(index.tree_descriptors_)
             : nullptr;
}
const ArcSearchPointI16* IndexInternals::tree_points_i16(const ModelIndex& index) {
  return index.descriptor_encoding() == DescriptorEncoding::kInt16
             ? reinterpret_cast<const ArcSearchPointI16*>(index.tree_descriptors_)
             : nullptr;
}
const ArcSearchPointI8* IndexInternals::tree_points_i8(const ModelIndex& index) {
  return index.descriptor_encoding() == DescriptorEncoding::kInt8
             ? reinterpret_cast<const ArcSearchPointI8*>(index.tree_descriptors_)
             : nullptr;
}
const ArcSearchPoint* IndexInternals::leaf_bounds_f32(const ModelIndex& index) {
  return index.descriptor_encoding() == DescriptorEncoding::kFloat32
             ? reinterpret_cast<const ArcSearchPoint*>(index.leaf_bounds_)
             : nullptr;
}
const ArcSearchPointI16* IndexInternals::leaf_bounds_i16(const ModelIndex& index) {
  return index.descriptor_encoding() == DescriptorEncoding::kInt16
             ? reinterpret_cast<const ArcSearchPointI16*>(index.leaf_bounds_)
             : nullptr;
}
const ArcSearchPointI8* IndexInternals::leaf_bounds_i8(const ModelIndex& index) {
  return index.descriptor_encoding() == DescriptorEncoding::kInt8
             ? reinterpret_cast<const ArcSearchPointI8*>(index.leaf_bounds_)
             : nullptr;
}
const KdNode* IndexInternals::tree_nodes_f32(const ModelIndex& index) {
  return index.descriptor_encoding() == DescriptorEncoding::kFloat32
             ? reinterpret_cast<const KdNode*>(index.tree_nodes_)
             : nullptr;
}
const KdNodeInt* IndexInternals::tree_nodes_int(const ModelIndex& index) {
  return index.descriptor_encoding() != DescriptorEncoding::kFloat32
             ? reinterpret_cast<const KdNodeInt*>(index.tree_nodes_)
             : nullptr;
}

}  // namespace kg
