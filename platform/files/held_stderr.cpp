#include "platform/files/held_stderr.h"

#include <unistd.h>

namespace kg::platform {

StderrHold::~StderrHold() {
  release(true);
  if (file_ != nullptr) std::fclose(file_);
}

void StderrHold::hold() {
  if (saved_ >= 0) return;
  if (file_ == nullptr) file_ = std::tmpfile();
  if (file_ == nullptr) return;
  std::fflush(stderr);
  std::rewind(file_);
  if (::ftruncate(::fileno(file_), 0) != 0) return;
  saved_ = ::dup(2);
  if (saved_ >= 0 && ::dup2(::fileno(file_), 2) < 0) {
    ::close(saved_);
    saved_ = -1;
  }
}

void StderrHold::release(bool pass_on) {
  if (saved_ < 0) return;
  std::fflush(stderr);
  ::dup2(saved_, 2);
  ::close(saved_);
  saved_ = -1;
  if (!pass_on) return;
  // Descriptor 2 wrote at the shared offset: the held text ends there.
  const off_t end = ::lseek(::fileno(file_), 0, SEEK_CUR);
  if (end <= 0) return;
  char buf[4096];
  off_t at = 0;
  while (at < end) {
    const ssize_t n = ::pread(::fileno(file_), buf, sizeof(buf), at);
    if (n <= 0) break;
    std::fwrite(buf, 1, static_cast<std::size_t>(n), stderr);
    at += n;
  }
  std::fflush(stderr);
}

}  // namespace kg::platform
