#pragma once
// The lock of an output folder: one mbi process writes into a folder at a time. It is the
// kernel's advisory lock (flock) on the folder itself, so no lock file is made, and the kernel
// releases it when the process ends however it ends (a crash or SIGKILL leaves no stale lock).
//
// mbi run holds its output folder's lock for the whole run, and refuses at once a folder another
// process holds; OutputSet::commit holds the lock of each output's folder while it moves the
// files into place (a few milliseconds), so the outputs of two commands never mix.
#include <chrono>
#include <filesystem>
#include <string>

namespace mbi::io {

class FolderLock {
 public:
  /// Locks the existing folder `dir`, waiting up to `wait` while another process holds it.
  /// Throws Error naming the folder and, when the system says which, the process holding it
  /// (its id and command line).
  explicit FolderLock(const std::filesystem::path& dir,
                      std::chrono::milliseconds wait = std::chrono::milliseconds(0));
  ~FolderLock();
  FolderLock(FolderLock&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  FolderLock& operator=(FolderLock&&) = delete;
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

/// The process holding an advisory lock on `dir` ("process 1234: mbi run a.toml --out o"), or ""
/// when none or unknown (read from /proc/locks).
std::string folder_lock_holder(const std::filesystem::path& dir);

}  // namespace mbi::io
