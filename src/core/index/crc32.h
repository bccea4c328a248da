// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320), as used by zlib and
// PNG, so checksums in a .kgi file can be verified with standard tools.
#pragma once

#include <cstddef>
#include <cstdint>

namespace kg {

// Continues a CRC: crc32(b, crc32(a)) == crc32(a followed by b). Start with 0.
std::uint32_t crc32(const void* data, std::size_t size, std::uint32_t crc = 0);

}  // namespace kg
