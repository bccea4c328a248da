// Output files written whole or not at all. The bytes go to a temporary file
// with a unique name (mkstemp) in the target's directory, which is renamed
// over the target when complete: readers of the target see the old file or
// the new one, never a part; two writers to one target never share a
// temporary; a user's file named like a temporary is never touched.
// Refused before anything is written: a target that exists and is not a
// regular file (a device node, a FIFO, a directory: never replaced), and a
// target that is one of the command's inputs (same device and inode).
// While a temporary exists, SIGINT, SIGTERM, SIGHUP and SIGPIPE remove it
// before the process ends (signal_cleanup.h; unless the program has its own
// handlers, as `live` does: it finishes the file and stops).
#pragma once

#include <string>
#include <vector>

#include "keygraph/status.h"

namespace kg::platform {

class OutputFile {
 public:
  OutputFile() = default;
  ~OutputFile();  // discard() unless committed
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  // Checks `target` as above against `inputs` and creates the temporary,
  // named ".<target name>.XXXXXX<suffix>" (the suffix keeps an extension
  // for encoders that choose the format by name). Errors name the target.
  Status create(const std::string& target, const std::vector<std::string>& inputs = {},
                const std::string& suffix = "");
  // The temporary's path and descriptor (-1 after close()).
  const std::string& temp_path() const { return temp_; }
  int fd() const { return fd_; }
  // Appends `size` bytes to the temporary.
  Status write(const void* data, std::size_t size);
  // Closes the descriptor, for writers that open temp_path() themselves.
  Status close();
  // Closes, checks the target once more and renames the temporary over it.
  Status commit();
  // Removes the temporary (nothing happens to the target).
  void discard();

 private:
  std::string target_;
  std::string temp_;
  int fd_ = -1;
  int slot_ = -1;  // in the signal handler's list of temporaries
};

// An error naming `target` unless it is absent or a regular file (a link
// to one counts as one: a rename replaces the link, never what it points to).
Status check_output_target(const std::string& target);

// Whether `a` and `b` name the same file (device and inode); false when
// either does not exist.
bool same_file(const std::string& a, const std::string& b);

}  // namespace kg::platform
