#include "platform/files/regular_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace kg::platform {

const char* file_type_name(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

Status open_regular_file(const std::string& path, int& fd, struct stat& info) {
  fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) {
    const int err = errno;
    if (err == ENOENT) return {StatusCode::kNotFound, path + ": no such file"};
    if (err == EACCES || err == EPERM) return {StatusCode::kIoError, path + ": permission denied"};
    if (err == ELOOP) return {StatusCode::kIoError, path + ": too many levels of symbolic links"};
    // A directory opens read-only on Linux; other systems say EISDIR.
    if (err == EISDIR) return {StatusCode::kIoError, path + ": is a directory"};
    return {StatusCode::kIoError, path + ": cannot open: " + std::strerror(err)};
  }
  if (::fstat(fd, &info) != 0) {
    const int err = errno;
    ::close(fd);
    fd = -1;
    return {StatusCode::kIoError, path + ": cannot stat: " + std::strerror(err)};
  }
  if (!S_ISREG(info.st_mode)) {
    ::close(fd);
    fd = -1;
    return {StatusCode::kIoError, path + ": is " + file_type_name(info.st_mode)};
  }
  return Status::ok();
}

Status read_regular_file(const std::string& path, std::vector<std::uint8_t>& bytes,
                         std::size_t max_bytes) {
  int fd = -1;
  struct stat info {};
  if (Status s = open_regular_file(path, fd, info); !s) return s;
  const auto size = static_cast<std::uint64_t>(info.st_size);
  if (size > max_bytes) {
    ::close(fd);
    return {StatusCode::kResourceExhausted, path + ": file of " + std::to_string(size) +
                                                " bytes is over the limit of " +
                                                std::to_string(max_bytes)};
  }
  bytes.resize(static_cast<std::size_t>(size));
  std::size_t got = 0;
  int err = 0;
  while (got < bytes.size()) {
    const ssize_t r = ::read(fd, bytes.data() + got, bytes.size() - got);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) err = errno;
    if (r <= 0) break;
    got += static_cast<std::size_t>(r);
  }
  // One byte more than fstat reported means the file grew meanwhile.
  std::uint8_t extra = 0;
  const bool longer = got == bytes.size() && err == 0 && ::read(fd, &extra, 1) > 0;
  ::close(fd);
  if (err != 0) return {StatusCode::kIoError, path + ": read failed: " + std::strerror(err)};
  if (got != bytes.size() || longer)
    return {StatusCode::kIoError, path + ": file changed while being read"};
  return Status::ok();
}

std::string byte_size_text(std::size_t bytes) {
  if (bytes >= (std::size_t{1} << 20) && bytes % (std::size_t{1} << 20) == 0)
    return std::to_string(bytes >> 20) + " MiB";
  if (bytes >= 1024 && bytes % 1024 == 0) return std::to_string(bytes >> 10) + " KiB";
  return std::to_string(bytes) + " bytes";
}

Status read_text_file(const std::string& path, std::string& text, std::size_t max_bytes,
                      const char* kind) {
  std::vector<std::uint8_t> bytes;
  Status s = read_regular_file(path, bytes, max_bytes);
  if (s.code() == StatusCode::kResourceExhausted) {
    struct stat info {};
    const long long size = ::stat(path.c_str(), &info) == 0 ? info.st_size : -1;
    return {StatusCode::kResourceExhausted,
            path + ": " + (size >= 0 ? std::to_string(size) + " bytes" : "too large") +
                ", over the " + byte_size_text(max_bytes) + " " + kind + " may have"};
  }
  if (!s) return s;
  text.assign(bytes.begin(), bytes.end());
  return Status::ok();
}

}  // namespace kg::platform
