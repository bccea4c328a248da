#include "platform/files/jpeg_structure.h"

namespace kg::platform {

namespace {

constexpr std::uint8_t kSoi = 0xD8, kEoi = 0xD9, kSos = 0xDA, kTem = 0x01;

bool is_restart(std::uint8_t marker) {
  return marker >= 0xD0 && marker <= 0xD7;
}

}  // namespace

bool is_jpeg(const std::uint8_t* data, std::size_t size) {
  return size >= 3 && data[0] == 0xFF && data[1] == kSoi && data[2] == 0xFF;
}

bool jpeg_is_complete(const std::uint8_t* data, std::size_t size) {
  std::size_t pos = 2;
  for (;;) {
    // Next marker: 0xFF, any fill bytes 0xFF, then the marker code. Bytes
    // before it that are not 0xFF are tolerated (libjpeg skips them too).
    while (pos < size && data[pos] != 0xFF) ++pos;
    while (pos < size && data[pos] == 0xFF) ++pos;
    if (pos >= size) return false;
    const std::uint8_t marker = data[pos++];
    if (marker == kEoi) return true;
    if (marker == 0x00 || marker == kTem || is_restart(marker) || marker == kSoi) continue;
    // A segment: a 2-byte big-endian length that counts itself.
    if (size - pos < 2) return false;
    const std::size_t length = (static_cast<std::size_t>(data[pos]) << 8) | data[pos + 1];
    if (length < 2 || size - pos < length) return false;
    pos += length;
    if (marker != kSos) continue;
    // Entropy-coded data up to the next marker that is not a stuffed 0xFF00
    // or a restart marker.
    for (;;) {
      while (pos < size && data[pos] != 0xFF) ++pos;
      std::size_t next = pos;
      while (next < size && data[next] == 0xFF) ++next;
      if (next >= size) return false;
      if (data[next] == 0x00 || is_restart(data[next])) {
        pos = next + 1;
        continue;
      }
      break;  // pos is at the next marker's 0xFF
    }
  }
}

}  // namespace kg::platform
