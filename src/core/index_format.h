// Byte layout of the .kgi model index, shared by the reader (core) and the
// writer (desktop builder). docs/FORMAT.md is the specification; every
// number here is little-endian and fixed-width.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "keygraph/params.h"
#include "keygraph/status.h"
#include "keygraph/types.h"

namespace kg::format {

// PNG-style magic: the high-bit byte catches 7-bit transfers, CR LF and the
// SUB/LF tail catch text-mode conversions and `type` on DOS.
inline constexpr std::uint8_t kMagic[8] = {0x89, 'K', 'G', 'I', '\r', '\n', 0x1A, '\n'};
inline constexpr std::uint16_t kVersionMajor = 1;
inline constexpr std::uint16_t kVersionMinor = 1;  // 1.1: vertex descriptors
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

inline constexpr std::size_t kParamsSize = 256;  // room for later parameters
inline constexpr std::size_t kSectionEntrySize = 32;
// Section table entry fields (byte offsets within an entry).
inline constexpr std::size_t kEntId = 0;
inline constexpr std::size_t kEntEncoding = 4;
inline constexpr std::size_t kEntOffset = 8;
inline constexpr std::size_t kEntSize = 16;
inline constexpr std::size_t kEntCount = 24;
inline constexpr std::size_t kEntCrc = 28;

enum SectionId : std::uint32_t {
  kSectionModels = 1,       // ModelRecord per model
  kSectionStrings = 2,      // UTF-8 model names
  kSectionKeypoints = 3,    // float32 x, y per keypoint
  kSectionArcs = 4,         // uint32 from, to per arc (global keypoint ids)
  kSectionDescriptors = 5,  // per tree slot: kDescriptorSize components
  kSectionTreeIds = 6,      // uint32 arc id per tree slot
  kSectionTreeNodes = 7,    // float32 split, uint32 dimension per internal node
  // Format 1.1: kVertexDescriptorSize bytes (SIFT) per keypoint, or empty.
  kSectionVertexDescriptors = 8,
};
// Sections 1..kSectionCount are in every index (format 1.0) and required.
// The writer writes every section up to kLastSectionId, empty or not; the
// reader takes a later section that is absent as empty, so 1.0 files load.
inline constexpr std::uint32_t kSectionCount = 7;
inline constexpr std::uint32_t kLastSectionId = 8;

enum DescriptorEncoding : std::uint32_t { kFloat32 = 0 };

// Model record (kModelRecordSize bytes).
inline constexpr std::size_t kModelRecordSize = 80;
inline constexpr std::size_t kModNameOffset = 0;
inline constexpr std::size_t kModNameLength = 4;
inline constexpr std::size_t kModWidth = 8;
inline constexpr std::size_t kModHeight = 12;
inline constexpr std::size_t kModKeypointBegin = 16;
inline constexpr std::size_t kModKeypointCount = 20;
inline constexpr std::size_t kModArcBegin = 24;
inline constexpr std::size_t kModArcCount = 28;
inline constexpr std::size_t kModKeygraphCount = 32;
inline constexpr std::size_t kModOutline = 40;  // 8 x float32

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

// Parameters block <-> Params. parse_params validates every value.
void serialize_params(const Params& params, std::uint8_t* out /* kParamsSize bytes */);
Status parse_params(const std::uint8_t* in, std::size_t size, Params& params);
// Same checks for parameters given programmatically (builder, CLI).
Status validate_params(const Params& params);

}  // namespace kg::format
