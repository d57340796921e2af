#pragma once
// A file for data a long command keeps until its end but not in memory (the per-frame records
// of metrics.json, the Bezier points of the 3D pictures): it lives on the disk of its folder,
// has no name (made with O_TMPFILE, or unlinked at once), and disappears when it is closed or
// the process ends, however it ends.
#include <cstdio>
#include <filesystem>
#include <string>

namespace mbi::io {

class ScratchFile {
 public:
  /// A new empty file in the existing folder `dir`; `what` names it in messages. Throws Error.
  ScratchFile(const std::filesystem::path& dir, std::string what);
  ~ScratchFile();
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;

  /// Appends bytes at the end, all or nothing: when the disk is full, what was written of them
  /// is dropped and Error thrown; the file holds what it held before.
  void append(const void* data, std::size_t bytes);
  /// Bytes held.
  long size() const { return size_; }
  /// Drops the bytes from `size` on (size <= size()).
  void truncate(long size);
  /// Reads `bytes` at byte `offset` (written before); throws Error when they are not there.
  void read(long offset, void* data, std::size_t bytes) const;

 private:
  int fd_ = -1;
  long size_ = 0;
  std::string what_;
};

}  // namespace mbi::io
