// Opening input files safely: only regular files, never a blocking open.
// An index or image path that names a FIFO would block open() forever, a
// directory or /dev/zero would be read as garbage or endlessly; these
// helpers open without blocking (O_NONBLOCK), check the type with fstat, and
// name in their error what the path is.
#pragma once

#include <sys/stat.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "keygraph/status.h"

namespace kg::platform {

// "a directory", "a FIFO", "a character device", "a block device", "a
// socket" or "not a regular file".
const char* file_type_name(mode_t mode);

// Opens `path` read-only (close-on-exec, non-blocking) and checks that it is
// a regular file; fills `info` from fstat. Errors name the path and the
// reason: missing (kNotFound: "no such file"), "permission denied", "too many
// levels of symbolic links", "is a directory", "is a FIFO", ... (kIoError).
Status open_regular_file(const std::string& path, int& fd, struct stat& info);

// open_regular_file, then the whole file into `bytes` (capacity reused).
// Files over `max_bytes` are refused before anything is read
// (kResourceExhausted), as are files that change size while read.
Status read_regular_file(const std::string& path, std::vector<std::uint8_t>& bytes,
                         std::size_t max_bytes);

// The same for the tools' text inputs (manifests, models.json, corners.txt,
// homography files): the whole file into `text`. A file over `max_bytes` is
// refused before anything is read, with a message naming `kind` and the
// limit: "PATH: 70000000 bytes, over the 64 MiB a manifest may have".
Status read_text_file(const std::string& path, std::string& text, std::size_t max_bytes,
                      const char* kind);
// "64 MiB", "4 KiB", "100 bytes": a byte count for messages.
std::string byte_size_text(std::size_t bytes);

}  // namespace kg::platform
