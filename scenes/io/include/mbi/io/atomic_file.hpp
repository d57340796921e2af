#pragma once
// The one atomic file writer of mbi. Every output file (meshes, point caches, VTK, PNG, JSON,
// TetGen files) is written through it: the bytes go to a temporary file with a unique name in the
// target's folder (created exclusively, so no existing file is ever reused or replaced), and only
// commit() renames it over the target. Destroyed without commit() (an exception, a failed
// check), it removes the temporary file, so a failed write leaves neither a half-written target
// nor a stray temporary behind.
#include <mbi/io/io.hpp>

#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>

namespace mbi::io {

class AtomicFile {
 public:
  /// Opens a fresh temporary file beside `target`. Throws IoError naming the target if its
  /// folder does not exist or is not writable.
  explicit AtomicFile(const std::filesystem::path& target);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// Appends bytes; throws IoError on a write error.
  void write(const void* data, std::size_t bytes);
  void write(const std::string& text);
  /// Moves to an absolute byte offset (to patch a header before commit()).
  void seek(long offset);
  /// Flushes, closes and renames the temporary file over the target.
  void commit();
  /// The open stream (valid until commit()).
  std::FILE* stream() const { return file_; }
  const std::filesystem::path& target() const { return target_; }
  const std::filesystem::path& temporary() const { return temporary_; }

 private:
  std::filesystem::path target_, temporary_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
};

/// Writes `target` atomically: `body` fills an AtomicFile, which is committed when it returns.
void write_file_atomic(const std::filesystem::path& target,
                       const std::function<void(AtomicFile&)>& body);
/// Writes `text` to `target` atomically.
void write_text_atomic(const std::filesystem::path& target, const std::string& text);

}  // namespace mbi::io
