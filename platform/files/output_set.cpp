#include "platform/files/output_set.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "platform/files/output_file.h"
#include "platform/files/regular_file.h"
#include "platform/files/signal_cleanup.h"

namespace kg::platform {

namespace {

namespace fs = std::filesystem;

// Staged files are numbered with 8 digits (signal_cleanup.h).
constexpr std::size_t kMaxStaged = 100000000;

Status io_error(const std::string& path, const std::string& what, int err) {
  return {StatusCode::kIoError, path + ": " + what + ": " + std::strerror(err)};
}

// "a file", "a FIFO", ...: what is in the way of a directory.
const char* in_the_way(mode_t mode) {
  return S_ISREG(mode) ? "a file" : file_type_name(mode);
}

// Makes `dir` and its missing parents; `made` gets those it made, outermost first.
Status make_directories(const std::string& dir, std::vector<std::string>& made) {
  std::vector<std::string> missing;
  fs::path start = fs::path(dir).lexically_normal();
  if (!start.has_filename() && start.has_parent_path()) start = start.parent_path();  // "a/"
  for (fs::path p = start; !p.empty() && p != p.root_path(); p = p.parent_path()) {
    struct stat info {};
    if (::stat(p.c_str(), &info) == 0) {
      if (!S_ISDIR(info.st_mode))
        return {StatusCode::kIoError,
                p.string() + ": is " + in_the_way(info.st_mode) + ", not a directory"};
      break;
    }
    if (errno != ENOENT) return io_error(p.string(), "cannot create the directory", errno);
    missing.push_back(p.string());
  }
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    if (::mkdir(it->c_str(), 0777) != 0 && errno != EEXIST)
      return io_error(*it, "cannot create the directory", errno);
    made.push_back(*it);
  }
  return Status::ok();
}

Status write_all(int fd, const void* data, std::size_t size, const std::string& target) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  while (size > 0) {
    const ssize_t w = ::write(fd, p, size);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return io_error(target, "write failed", w < 0 ? errno : ENOSPC);
    p += w;
    size -= static_cast<std::size_t>(w);
  }
  return Status::ok();
}

}  // namespace

OutputSet::OutputSet(std::string root, std::vector<std::string> inputs)
    : root_(root.empty() ? std::string(".") : std::move(root)), inputs_(std::move(inputs)) {
  // Each input's identity once: a report may be checked against thousands.
  for (std::size_t i = 0; i < inputs_.size(); ++i) {
    struct stat info {};
    if (::stat(inputs_[i].c_str(), &info) == 0)
      identities_.push_back({info.st_dev, info.st_ino, i});
  }
}

const std::string* OutputSet::input_at(const std::string& path) const {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) return nullptr;
  for (const Identity& id : identities_) {
    if (id.device == info.st_dev && id.inode == info.st_ino) return &inputs_[id.input];
  }
  return nullptr;
}

OutputSet::~OutputSet() {
  discard();
}

Status OutputSet::check(const std::string& target) const {
  if (target.empty() || target.back() == '/')
    return {StatusCode::kInvalidArgument, "'" + target + "': not a file name"};
  if (Status s = check_output_target(target); !s) return s;
  const std::string key = fs::path(target).lexically_normal().string();
  if (keys_.count(key) != 0)
    return {StatusCode::kInvalidArgument, target + ": written twice by one command"};
  if (const std::string* input = input_at(target)) {
    return {StatusCode::kInvalidArgument,
            target + ": is also an input (" + *input + "); choose another output"};
  }
  return Status::ok();
}

Status OutputSet::start() {
  if (!staging_.empty()) return Status::ok();
  if (Status s = make_directories(root_, created_); !s) {
    discard();
    return s;
  }
  std::string dir = (fs::path(root_) / ".keygraph-XXXXXX").string();
  if (::mkdtemp(dir.data()) == nullptr) {
    const Status s = io_error(root_, "cannot create a directory for the outputs", errno);
    discard();
    return s;
  }
  staging_ = dir;
  registered_ = cleanup::register_staging(staging_, created_);
  return Status::ok();
}

Status OutputSet::add(const std::string& target, const void* data, std::size_t size) {
  if (Status s = check(target); !s) return s;
  if (targets_.size() >= kMaxStaged)
    return {StatusCode::kResourceExhausted, target + ": too many output files"};
  if (Status s = start(); !s) return s;
  const std::string staged = staging_ + "/" + cleanup::staged_name(targets_.size());
  if (registered_) cleanup::set_staged_count(targets_.size() + 1);
  const int fd = ::open(staged.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) return io_error(target, "cannot create", errno);
  Status s = write_all(fd, data, size, target);
  if (::close(fd) != 0 && s) s = io_error(target, "write failed", errno);
  if (!s) {
    ::unlink(staged.c_str());
    return s;
  }
  targets_.push_back(target);
  keys_.insert(fs::path(target).lexically_normal().string());
  return Status::ok();
}

void OutputSet::remove_at_commit(const std::string& path) {
  removals_.push_back(path);
}

Status OutputSet::commit() {
  // Every target once more (it may have changed since it was added), and
  // its directory, before the first rename.
  std::vector<std::string> made;
  for (const std::string& target : targets_) {
    Status s = check_output_target(target);
    if (s) s = make_directories(fs::path(target).parent_path().string(), made);
    if (!s) {
      for (auto it = made.rbegin(); it != made.rend(); ++it) ::rmdir(it->c_str());
      discard();
      return s;
    }
  }
  for (std::size_t i = 0; i < targets_.size(); ++i) {
    const std::string staged = staging_ + "/" + cleanup::staged_name(i);
    if (::rename(staged.c_str(), targets_[i].c_str()) != 0) {
      const int err = errno;
      // The staged files still there are removed by discard().
      Status s{StatusCode::kIoError,
               targets_[i] + ": cannot rename into place: " + std::strerror(err) +
                   (i > 0 ? " (" + std::to_string(i) + " of the " +
                                std::to_string(targets_.size()) + " outputs were written)"
                          : "")};
      if (i > 0) created_.clear();  // root_ now holds outputs: keep it
      discard();
      return s;
    }
  }
  for (const std::string& path : removals_) {
    struct stat info {};
    if (::lstat(path.c_str(), &info) != 0) continue;
    if (input_at(path) != nullptr) continue;
    if (S_ISDIR(info.st_mode)) {
      ::rmdir(path.c_str());  // only when empty
    } else if (S_ISREG(info.st_mode) || S_ISLNK(info.st_mode)) {
      ::unlink(path.c_str());
    }
  }
  // Done: what is left is the empty staging directory; root_ stays.
  targets_.clear();
  created_.clear();
  discard();
  return Status::ok();
}

void OutputSet::discard() {
  if (!staging_.empty()) {
    for (std::size_t i = 0; i < targets_.size() + 1; ++i)
      ::unlink((staging_ + "/" + cleanup::staged_name(i)).c_str());
    ::rmdir(staging_.c_str());
  }
  for (auto it = created_.rbegin(); it != created_.rend(); ++it) ::rmdir(it->c_str());
  if (registered_) cleanup::unregister_staging();
  registered_ = false;
  staging_.clear();
  created_.clear();
  targets_.clear();
  keys_.clear();
  removals_.clear();
}

Status check_output_directory(const std::string& dir) {
  fs::path p = fs::path(dir.empty() ? "." : dir).lexically_normal();
  if (!p.has_filename() && p.has_parent_path()) p = p.parent_path();
  for (;; p = p.parent_path()) {
    struct stat info {};
    const std::string path = p.empty() ? "." : p.string();
    if (::stat(path.c_str(), &info) == 0) {
      if (S_ISDIR(info.st_mode)) return Status::ok();
      return {StatusCode::kInvalidArgument,
              path + ": is " + in_the_way(info.st_mode) + ", not a directory"};
    }
    // Missing, or under a file: the ancestor says which.
    if (errno != ENOENT && errno != ENOTDIR)
      return io_error(path, "cannot use as a directory", errno);
    if (p.empty()) return Status::ok();
  }
}

}  // namespace kg::platform
