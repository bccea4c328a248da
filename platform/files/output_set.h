// Several output files written all or nothing: a report of many files, a
// manifest and its models.json. Every target is checked when it is added
// (OutputSet::check() can check them all before the first one is written):
// a file name; absent, a regular file or a link to one (the link is
// replaced, never followed); no path component that exists and is not a
// directory; not one of the command's inputs (device and inode); not added
// twice. The contents go to numbered files in one staging directory
// (".keygraph-XXXXXX" in `root`, made at the first add()), so memory holds
// one file at a time; commit() creates the targets' directories and renames
// the staged files into place. Until then nothing but the staging directory
// exists: discard(), the destructor, or SIGINT, SIGTERM, SIGHUP and SIGPIPE
// (signal_cleanup.h) remove it, and `root` and its parents again if the set
// created them. commit() checks every target once more before the first
// rename; only a failing rename (a full disk cannot make one fail) can then
// leave some targets replaced and others not, and its error says so.
#pragma once

#include <sys/types.h>

#include <cstddef>
#include <set>
#include <string>
#include <vector>

#include "keygraph/status.h"

namespace kg::platform {

class OutputSet {
 public:
  // `root`: the directory the outputs go in (and the staging directory);
  // `inputs`: files no output may be.
  OutputSet(std::string root, std::vector<std::string> inputs);
  ~OutputSet();
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;

  // The checks above for one target, without adding it; the error names it.
  Status check(const std::string& target) const;
  // check(), then stages `size` bytes as the target's content.
  Status add(const std::string& target, const void* data, std::size_t size);
  Status add(const std::string& target, const std::string& text) {
    return add(target, text.data(), text.size());
  }
  // A file (or empty directory) to remove when committing, after the
  // renames: an earlier run's output that this one does not replace. Only
  // regular files, links and empty directories are removed, never an input.
  void remove_at_commit(const std::string& path);
  // Creates the targets' directories and renames every staged file into
  // place, then the removals. With nothing staged, nothing is created.
  Status commit();
  // Removes the staging directory, and `root` if the set made it.
  void discard();

  const std::vector<std::string>& targets() const { return targets_; }

 private:
  struct Identity {
    dev_t device;
    ino_t inode;
    std::size_t input;
  };
  Status start();
  // The input `path` names (device and inode), or null.
  const std::string* input_at(const std::string& path) const;

  std::string root_;
  std::vector<std::string> inputs_;
  std::vector<Identity> identities_;
  std::vector<std::string> targets_;
  std::set<std::string> keys_;  // targets lexically normalised
  std::vector<std::string> removals_;
  std::vector<std::string> created_;  // directories made for root_, outermost first
  std::string staging_;
  bool registered_ = false;
};

// An error unless `dir` is a directory or could be made one (nothing in
// the way: its nearest existing ancestor is a directory). Creates nothing:
// an OutputSet rooted there makes it when it writes.
Status check_output_directory(const std::string& dir);

}  // namespace kg::platform
