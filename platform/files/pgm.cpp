#include "platform/files/pgm.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

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
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    return {err == ENOENT ? StatusCode::kNotFound : StatusCode::kIoError,
            path + ": cannot open: " + std::strerror(err)};
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return {StatusCode::kIoError, path + ": not a regular file"};
  }
  const std::size_t size = static_cast<std::size_t>(st.st_size);
  bytes.resize(size);
  std::size_t got = 0;
  while (got < size) {
    const ssize_t r = ::read(fd, bytes.data() + got, size - got);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) break;
    got += static_cast<std::size_t>(r);
  }
  const int err = errno;
  ::close(fd);
  if (got != size) {
    return {StatusCode::kIoError, path + ": read " + std::to_string(got) + " of " +
                                      std::to_string(size) + " bytes" +
                                      (got < size ? std::string(": ") + std::strerror(err) : "")};
  }
  return Status::ok();
}

Status read_pgm(const std::string& path, GrayImage& out) {
  std::vector<std::uint8_t> bytes;
  if (Status s = read_file(path, bytes); !s) return s;
  return decode_pgm(bytes.data(), bytes.size(), path, out);
}

Status write_pgm(const std::string& path, const ImageView& image) {
  if (image.empty()) return {StatusCode::kInvalidArgument, path + ": empty image"};
  std::string tmp = path + ".tmp.XXXXXX";
  const int fd = ::mkstemp(tmp.data());
  if (fd < 0) {
    return {StatusCode::kIoError,
            path + ": cannot create a temporary file: " + std::strerror(errno)};
  }
  (void)::fchmod(fd, 0644);  // mkstemp creates 0600 files
  std::FILE* f = ::fdopen(fd, "wb");
  if (f == nullptr) {
    ::close(fd);
    ::unlink(tmp.c_str());
    return {StatusCode::kIoError, path + ": fdopen failed"};
  }
  bool ok = std::fprintf(f, "P5\n%d %d\n255\n", image.width, image.height) > 0;
  for (int y = 0; ok && y < image.height; ++y) {
    ok = std::fwrite(image.row(y), 1, static_cast<std::size_t>(image.width), f) ==
         static_cast<std::size_t>(image.width);
  }
  ok = (std::fclose(f) == 0) && ok;
  if (!ok || std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    return {StatusCode::kIoError, path + ": write failed: " + std::strerror(err)};
  }
  return Status::ok();
}

}  // namespace kg::platform
