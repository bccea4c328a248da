#include "platform/files/output_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "platform/files/regular_file.h"
#include "platform/files/signal_cleanup.h"

namespace kg::platform {

Status check_output_target(const std::string& target) {
  struct stat info {};
  if (::stat(target.c_str(), &info) != 0) {
    const int err = errno;
    if (err == ENOENT) return Status::ok();
    if (err == EACCES) return {StatusCode::kIoError, target + ": permission denied"};
    if (err == ELOOP) return {StatusCode::kIoError, target + ": too many levels of symbolic links"};
    if (err == ENOTDIR)
      return {StatusCode::kIoError, target + ": a path component is not a directory"};
    return {StatusCode::kIoError, target + ": " + std::strerror(err)};
  }
  if (!S_ISREG(info.st_mode)) {
    return {StatusCode::kInvalidArgument, target + ": is " + file_type_name(info.st_mode) +
                                              "; outputs replace regular files only"};
  }
  return Status::ok();
}

namespace {

std::string directory_of(const std::string& path) {
  const std::size_t slash = path.rfind('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

std::string name_of(const std::string& path) {
  const std::size_t slash = path.rfind('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

}  // namespace

bool same_file(const std::string& a, const std::string& b) {
  struct stat sa {
  }, sb{};
  return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev &&
         sa.st_ino == sb.st_ino;
}

OutputFile::~OutputFile() {
  discard();
}

Status OutputFile::create(const std::string& target, const std::vector<std::string>& inputs,
                          const std::string& suffix) {
  discard();
  if (target.empty() || target.back() == '/')
    return {StatusCode::kInvalidArgument, "'" + target + "': not a file name"};
  if (Status s = check_output_target(target); !s) return s;
  for (const std::string& input : inputs) {
    if (same_file(target, input)) {
      return {StatusCode::kInvalidArgument,
              target + ": is also an input (" + input + "); choose another output"};
    }
  }
  std::string temp = directory_of(target) + "/." + name_of(target) + ".XXXXXX" + suffix;
  const int fd = ::mkostemps(temp.data(), static_cast<int>(suffix.size()), O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    return {StatusCode::kIoError, target + ": cannot create a file in " + directory_of(target) +
                                      ": " + std::strerror(err)};
  }
  // mkstemp creates 0600; give the file the mode a plain create would.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  (void)::fchmod(fd, 0666 & ~mask);
  target_ = target;
  temp_ = temp;
  fd_ = fd;
  slot_ = cleanup::register_file(temp_);
  return Status::ok();
}

Status OutputFile::write(const void* data, std::size_t size) {
  if (fd_ < 0) return {StatusCode::kInvalidArgument, target_ + ": output not open"};
  const auto* p = static_cast<const std::uint8_t*>(data);
  while (size > 0) {
    const ssize_t w = ::write(fd_, p, size);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) {
      const int err = w < 0 ? errno : ENOSPC;
      return {StatusCode::kIoError, target_ + ": write failed: " + std::strerror(err)};
    }
    p += w;
    size -= static_cast<std::size_t>(w);
  }
  return Status::ok();
}

Status OutputFile::close() {
  if (fd_ < 0) return Status::ok();
  const int r = ::close(fd_);
  fd_ = -1;
  if (r != 0) return {StatusCode::kIoError, target_ + ": write failed: " + std::strerror(errno)};
  return Status::ok();
}

Status OutputFile::commit() {
  if (temp_.empty()) return {StatusCode::kInvalidArgument, target_ + ": output not open"};
  Status s = close();
  // The target may have changed since create(): replace regular files only.
  if (s) s = check_output_target(target_);
  if (s && ::rename(temp_.c_str(), target_.c_str()) != 0)
    s = {StatusCode::kIoError, target_ + ": cannot rename into place: " + std::strerror(errno)};
  if (!s) {
    discard();
    return s;
  }
  cleanup::unregister_file(slot_);
  slot_ = -1;
  temp_.clear();
  return Status::ok();
}

void OutputFile::discard() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!temp_.empty()) ::unlink(temp_.c_str());
  cleanup::unregister_file(slot_);
  slot_ = -1;
  temp_.clear();
}

}  // namespace kg::platform
