// image_header.h: each format's size fields, from its specification (PNG
// IHDR; JPEG SOFn, found by walking the marker segments; BMP
// BITMAPINFOHEADER or BITMAPCOREHEADER; TIFF tags 256 and 257 of the first
// IFD; WebP VP8X, VP8 and VP8L; netpbm headers; Sun raster).
#include "platform/files/image_header.h"

#include <cstring>

#include "platform/files/image_limits.h"

namespace kg::platform {

namespace {

using Kind = DeclaredSize::Kind;

std::uint32_t be16(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 8) | p[1];
}
std::uint32_t be32(const std::uint8_t* p) {
  return (be16(p) << 16) | be16(p + 2);
}
std::uint32_t le16(const std::uint8_t* p) {
  return std::uint32_t{p[0]} | (std::uint32_t{p[1]} << 8);
}
std::uint32_t le24(const std::uint8_t* p) {
  return le16(p) | (std::uint32_t{p[2]} << 16);
}
std::uint32_t le32(const std::uint8_t* p) {
  return le16(p) | (le16(p + 2) << 16);
}
std::uint64_t le64(const std::uint8_t* p) {
  return std::uint64_t{le32(p)} | (std::uint64_t{le32(p + 4)} << 32);
}
bool starts(const std::uint8_t* data, std::size_t size, const char* magic, std::size_t n) {
  return size >= n && std::memcmp(data, magic, n) == 0;
}

DeclaredSize known(const char* format, std::uint64_t width, std::uint64_t height) {
  DeclaredSize d;
  d.format = format;
  if (width == 0 || height == 0) {
    d.kind = Kind::kUnreadable;
    return d;
  }
  d.kind = Kind::kKnown;
  d.width = width;
  d.height = height;
  return d;
}
DeclaredSize unreadable(const char* format) {
  DeclaredSize d;
  d.kind = Kind::kUnreadable;
  d.format = format;
  return d;
}

DeclaredSize png(const std::uint8_t* d, std::size_t size) {
  // Signature, then the IHDR chunk first: length, "IHDR", width, height.
  if (size < 24 || std::memcmp(d + 12, "IHDR", 4) != 0) return unreadable("PNG");
  return known("PNG", be32(d + 16), be32(d + 20));
}

DeclaredSize jpeg(const std::uint8_t* d, std::size_t size) {
  std::size_t i = 2;
  while (i + 1 < size) {
    if (d[i] != 0xFF) return unreadable("JPEG");
    while (i + 1 < size && d[i + 1] == 0xFF) ++i;  // fill bytes
    if (i + 1 >= size) break;
    const std::uint8_t m = d[i + 1];
    i += 2;
    if (m == 0x01 || (m >= 0xD0 && m <= 0xD7)) continue;  // no length
    if (m == 0xD9 || m == 0xDA) break;                    // end, or a scan before any frame
    if (i + 2 > size) break;
    const std::size_t length = be16(d + i);
    const bool frame = m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC;
    if (frame) {
      if (length < 8 || i + 7 > size) break;
      return known("JPEG", be16(d + i + 5), be16(d + i + 3));  // precision, height, width
    }
    if (length < 2) break;
    i += length;
  }
  return unreadable("JPEG");
}

DeclaredSize bmp(const std::uint8_t* d, std::size_t size) {
  if (size < 26) return unreadable("BMP");
  if (le32(d + 14) == 12) return known("BMP", le16(d + 18), le16(d + 20));  // OS/2 core header
  const auto height = static_cast<std::int32_t>(le32(d + 22));              // < 0: top-down
  return known("BMP", static_cast<std::int32_t>(le32(d + 18)) < 0 ? 0 : le32(d + 18),
               height < 0 ? std::uint64_t{0} - static_cast<std::int64_t>(height)
                          : static_cast<std::uint64_t>(height));
}

// TIFF and BigTIFF: the first IFD's ImageWidth (256) and ImageLength (257).
DeclaredSize tiff(const std::uint8_t* d, std::size_t size) {
  const bool little = d[0] == 'I';
  auto u16 = [&](std::size_t at) { return little ? le16(d + at) : be16(d + at); };
  auto u32 = [&](std::size_t at) { return little ? le32(d + at) : be32(d + at); };
  auto u64 = [&](std::size_t at) {
    return little ? le64(d + at) : (std::uint64_t{be32(d + at)} << 32) | be32(d + at + 4);
  };
  const bool big = u16(2) == 43;
  if (size < (big ? 16u : 8u)) return unreadable("TIFF");
  const std::uint64_t ifd = big ? u64(8) : u32(4);
  const std::size_t count_bytes = big ? 8 : 2, entry_bytes = big ? 20 : 12;
  if (ifd > size || size - ifd < count_bytes) return unreadable("TIFF");
  const auto first = static_cast<std::size_t>(ifd);  // < size: fits
  const std::uint64_t entries = big ? u64(first) : u16(first);
  // Entries the data holds after the count; more declared is a truncated IFD.
  const std::size_t room = (size - first - count_bytes) / entry_bytes;
  std::uint64_t width = 0, height = 0;
  for (std::uint64_t e = 0; e < entries; ++e) {
    if (e >= room) return unreadable("TIFF");
    const std::size_t at = first + count_bytes + static_cast<std::size_t>(e) * entry_bytes;
    const std::uint32_t tag = u16(at), type = u16(at + 2);
    const std::size_t value = at + (big ? 12 : 8);
    std::uint64_t v = 0;
    if (type == 3)
      v = u16(value);  // SHORT
    else if (type == 4)
      v = u32(value);  // LONG
    else if (type == 16 && big)
      v = u64(value);  // LONG8
    if (tag == 256) width = v;
    if (tag == 257) height = v;
  }
  return known("TIFF", width, height);
}

DeclaredSize webp(const std::uint8_t* d, std::size_t size) {
  if (size < 30) return unreadable("WebP");
  if (std::memcmp(d + 12, "VP8X", 4) == 0)
    // Canvas width and height minus one, 24 bits each at 24 and 27 (the
    // header's last byte is d[29]: reading 4 bytes at 27 ran past a 30-byte
    // file, fuzz_pgm).
    return known("WebP", le24(d + 24) + 1, le24(d + 27) + 1);
  if (std::memcmp(d + 12, "VP8 ", 4) == 0) {
    if (d[23] != 0x9D || d[24] != 0x01 || d[25] != 0x2A) return unreadable("WebP");
    return known("WebP", le16(d + 26) & 0x3FFF, le16(d + 28) & 0x3FFF);
  }
  if (std::memcmp(d + 12, "VP8L", 4) == 0) {
    if (d[20] != 0x2F) return unreadable("WebP");
    const std::uint32_t bits = le32(d + 21);
    return known("WebP", (bits & 0x3FFF) + 1, ((bits >> 14) & 0x3FFF) + 1);
  }
  return unreadable("WebP");
}

// netpbm: P1-P6 and PFM ("PF", "Pf"): width and height, the first two
// numbers after the magic (whitespace and '#' comments between); PAM (P7):
// its WIDTH and HEIGHT lines.
DeclaredSize netpbm(const std::uint8_t* d, std::size_t size) {
  const char* format = d[1] == '7' ? "PAM" : (d[1] == 'F' || d[1] == 'f') ? "PFM" : "PNM";
  std::size_t i = 2;
  auto skip_space = [&] {
    while (i < size &&
           (d[i] == ' ' || d[i] == '\t' || d[i] == '\r' || d[i] == '\n' || d[i] == '#')) {
      if (d[i] == '#')
        while (i < size && d[i] != '\n') ++i;
      else
        ++i;
    }
  };
  auto number = [&](std::uint64_t& out) {
    skip_space();
    const std::size_t start = i;
    out = 0;
    while (i < size && d[i] >= '0' && d[i] <= '9' && out < (std::uint64_t{1} << 40))
      out = out * 10 + static_cast<std::uint64_t>(d[i++] - '0');
    return i > start;
  };
  std::uint64_t width = 0, height = 0;
  if (d[1] != '7') {
    if (!number(width) || !number(height)) return unreadable(format);
    return known(format, width, height);
  }
  while (i < size && (width == 0 || height == 0)) {
    skip_space();
    auto keyword = [&](const char* k) {
      const std::size_t n = std::strlen(k);
      return size - i >= n && std::memcmp(d + i, k, n) == 0 && (i += n, true);
    };
    if (keyword("ENDHDR")) break;
    if (keyword("WIDTH")) {
      if (!number(width)) break;
    } else if (keyword("HEIGHT")) {
      if (!number(height)) break;
    } else {
      while (i < size && d[i] != '\n') ++i;
    }
  }
  return known(format, width, height);
}

DeclaredSize unchecked(const char* format) {
  DeclaredSize d;
  d.kind = Kind::kUnchecked;
  d.format = format;
  return d;
}

}  // namespace

DeclaredSize declared_image_size(const std::uint8_t* data, std::size_t size) {
  if (starts(data, size, "\x89PNG\r\n\x1a\n", 8)) return png(data, size);
  if (starts(data, size, "\xFF\xD8", 2)) return jpeg(data, size);
  if (starts(data, size, "BM", 2)) return bmp(data, size);
  if (starts(data, size, "II*\0", 4) || starts(data, size, "MM\0*", 4) ||
      starts(data, size, "II+\0", 4) || starts(data, size, "MM\0+", 4))
    return tiff(data, size);
  if (starts(data, size, "RIFF", 4) && size >= 12 && std::memcmp(data + 8, "WEBP", 4) == 0)
    return webp(data, size);
  if (size >= 3 && data[0] == 'P' &&
      ((data[1] >= '1' && data[1] <= '7') || data[1] == 'F' || data[1] == 'f') &&
      (data[2] == ' ' || data[2] == '\t' || data[2] == '\r' || data[2] == '\n'))
    return netpbm(data, size);
  if (starts(data, size, "\x59\xA6\x6A\x95", 4))
    return size >= 12 ? known("Sun raster", be32(data + 4), be32(data + 8))
                      : unreadable("Sun raster");
  if (starts(data, size, "\xFF\x4F\xFF\x51", 4) ||
      starts(data, size, "\x00\x00\x00\x0C\x6A\x50\x20\x20", 8))
    return unchecked("JPEG 2000");
  if (starts(data, size, "\x76\x2F\x31\x01", 4)) return unchecked("OpenEXR");
  if (starts(data, size, "#?RADIANCE", 10) || starts(data, size, "#?RGBE", 6))
    return unchecked("Radiance HDR");
  return {};
}

Status check_declared_size(const std::vector<std::uint8_t>& bytes, const std::string& path,
                           int reduction) {
  const DeclaredSize d = declared_image_size(bytes.data(), bytes.size());
  if (d.kind == Kind::kUnchecked)
    return {StatusCode::kInvalidArgument,
            path + ": " + d.format +
                " images are not read: their size cannot be checked before decoding (convert it "
                "to PNG or JPEG)"};
  if (d.kind != Kind::kKnown) return Status::ok();
  const std::uint64_t r = reduction > 1 ? static_cast<std::uint64_t>(reduction) : 1;
  const std::uint64_t w = (d.width + r - 1) / r, h = (d.height + r - 1) / r;
  // Sides below 2^32 each: the product cannot overflow.
  if (w <= static_cast<std::uint64_t>(kMaxImagePixels) &&
      h <= static_cast<std::uint64_t>(kMaxImagePixels) &&
      w * h <= static_cast<std::uint64_t>(kMaxImagePixels))
    return Status::ok();
  return {StatusCode::kResourceExhausted,
          path + ": " + d.format + " of " + std::to_string(d.width) + "x" +
              std::to_string(d.height) + " pixels" +
              (r > 1 ? " (1/" + std::to_string(r) + ": " + std::to_string(w) + "x" +
                           std::to_string(h) + ")"
                     : std::string()) +
              " is over " + std::to_string(kMaxImagePixels) + " pixels (the limit), not decoded"};
}

}  // namespace kg::platform
