// The system calls the V4L2 source makes, behind an interface so that tests
// can stand in for a camera (short buffers, a device that disappears, a
// stalled stream) on machines without one. Each method has the contract of
// the POSIX call it is named after: on failure it returns -1 (MAP_FAILED for
// mmap) and sets errno.
#pragma once

#include <poll.h>
#include <sys/stat.h>
#include <sys/types.h>

#include <cstddef>

namespace kg::platform::v4l2 {

class SystemIo {
 public:
  virtual ~SystemIo() = default;
  virtual int open(const char* path, int flags) = 0;
  virtual int close(int fd) = 0;
  virtual int fstat(int fd, struct stat* st) = 0;
  virtual int ioctl(int fd, unsigned long request, void* arg) = 0;
  virtual int poll(struct pollfd* fds, nfds_t count, int timeout_ms) = 0;
  virtual void* mmap(std::size_t length, int prot, int flags, int fd, off_t offset) = 0;
  virtual int munmap(void* addr, std::size_t length) = 0;
};

// The real system calls; lives for the whole program.
SystemIo& system_io();

}  // namespace kg::platform::v4l2
