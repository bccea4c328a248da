#include "platform/files/pgm.h"

#include <cstdio>
#include <cstring>
#include <string>

#include "platform/files/image_limits.h"
#include "platform/files/output_file.h"
#include "platform/files/regular_file.h"

namespace kg::platform {
namespace {

constexpr int kMaxSide = 1 << 15;

bool is_space(std::uint8_t c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

// Reads one header number after skipping whitespace and '#' comments.
bool header_number(const std::uint8_t* data, std::size_t size, std::size_t& pos, long& value) {
  for (;;) {
    while (pos < size && is_space(data[pos])) ++pos;
    if (pos < size && data[pos] == '#') {
      while (pos < size && data[pos] != '\n' && data[pos] != '\r') ++pos;
      continue;
    }
    break;
  }
  if (pos >= size || data[pos] < '0' || data[pos] > '9') return false;
  value = 0;
  while (pos < size && data[pos] >= '0' && data[pos] <= '9') {
    value = value * 10 + (data[pos] - '0');
    if (value > 1000000) return false;
    ++pos;
  }
  return true;
}

Status corrupt(const std::string& name, const std::string& what) {
  return {StatusCode::kCorruptData, name + ": " + what};
}

}  // namespace

bool is_pgm(const std::uint8_t* data, std::size_t size) {
  return size >= 2 && data[0] == 'P' && data[1] == '5';
}

Status decode_pgm(const std::uint8_t* data, std::size_t size, const std::string& name,
                  GrayImage& out) {
  if (!is_pgm(data, size)) {
    if (size >= 2 && data[0] == 'P' && data[1] >= '1' && data[1] <= '7') {
      return corrupt(name, std::string("P") + static_cast<char>(data[1]) +
                               " netpbm file: only binary gray PGM (P5) is supported");
    }
    return corrupt(name, "not a binary PGM file (no P5 magic)");
  }
  std::size_t pos = 2;
  if (pos >= size || !is_space(data[pos])) return corrupt(name, "malformed PGM header");
  long w = 0, h = 0, maxval = 0;
  if (!header_number(data, size, pos, w) || !header_number(data, size, pos, h) ||
      !header_number(data, size, pos, maxval)) {
    return corrupt(name, "malformed PGM header (width, height, maxval)");
  }
  if (w < 1 || h < 1 || w > kMaxSide || h > kMaxSide) {
    return corrupt(name, "PGM size " + std::to_string(w) + "x" + std::to_string(h) +
                             " outside 1.." + std::to_string(kMaxSide));
  }
  if (static_cast<long long>(w) * h > kMaxImagePixels) {
    return corrupt(name, "PGM size " + std::to_string(w) + "x" + std::to_string(h) + " is over " +
                             std::to_string(kMaxImagePixels) + " pixels (the limit)");
  }
  if (maxval < 1 || maxval > 65535) {
    return corrupt(name, "PGM maxval " + std::to_string(maxval) + " outside 1..65535");
  }
  if (pos >= size || !is_space(data[pos])) return corrupt(name, "malformed PGM header");
  ++pos;  // the single whitespace byte before the samples
  const std::size_t bytes_per_sample = maxval < 256 ? 1 : 2;
  const std::size_t count = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  const std::size_t needed = count * bytes_per_sample;
  if (size - pos < needed) {
    return corrupt(name, "truncated PGM: " + std::to_string(size - pos) + " of " +
                             std::to_string(needed) + " bytes of pixel data");
  }
  out.width = static_cast<int>(w);
  out.height = static_cast<int>(h);
  out.pixels.resize(count);
  const std::uint8_t* src = data + pos;
  const std::uint32_t m = static_cast<std::uint32_t>(maxval);
  if (bytes_per_sample == 1 && m == 255) {
    std::memcpy(out.pixels.data(), src, count);
  } else {
    for (std::size_t i = 0; i < count; ++i) {
      std::uint32_t v = bytes_per_sample == 1
                            ? src[i]
                            : (static_cast<std::uint32_t>(src[2 * i]) << 8) | src[2 * i + 1];
      if (v > m) v = m;
      out.pixels[i] = static_cast<std::uint8_t>((v * 255u + m / 2) / m);
    }
  }
  return Status::ok();
}

Status read_file(const std::string& path, std::vector<std::uint8_t>& bytes) {
  return read_regular_file(path, bytes, kMaxImageFileBytes);
}

Status read_pgm(const std::string& path, GrayImage& out) {
  std::vector<std::uint8_t> bytes;
  if (Status s = read_file(path, bytes); !s) return s;
  return decode_pgm(bytes.data(), bytes.size(), path, out);
}

Status write_pgm(const std::string& path, const ImageView& image,
                 const std::vector<std::string>& inputs) {
  if (image.empty()) return {StatusCode::kInvalidArgument, path + ": empty image"};
  OutputFile out;
  if (Status s = out.create(path, inputs); !s) return s;
  char header[48];
  const int n =
      std::snprintf(header, sizeof(header), "P5\n%d %d\n255\n", image.width, image.height);
  Status s = out.write(header, static_cast<std::size_t>(n));
  for (int y = 0; s && y < image.height; ++y)
    s = out.write(image.row(y), static_cast<std::size_t>(image.width));
  if (s) s = out.commit();
  return s;
}

}  // namespace kg::platform
