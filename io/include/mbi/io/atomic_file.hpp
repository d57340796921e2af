#pragma once
// The one atomic file writer of mbi. Every output file (meshes, point caches, VTK, PNG, JSON,
// TetGen files) is written through it: the bytes go to a temporary file with a unique name in the
// target's folder (created exclusively, so no existing file is ever reused or replaced), and only
// commit() renames it over the target. Destroyed without commit() (an exception, a failed
// check), it removes the temporary file, so a failed write leaves neither a half-written target
// nor a stray temporary behind.
//
// Temporary names start with kTemporaryPrefix (".mbi-tmp.") and carry the writer's process id,
// never the target's name (so any name a folder takes can be written, up to 255 bytes):
// "<folder>/.mbi-tmp.<pid>.<n>-<random>.tmp". A process killed with SIGKILL can leave one behind
// (never a partial file under a final name); remove_stale_temporaries() removes those whose
// process is gone (mbi run --force does so in its folder), and remove_temporaries_now() those of
// this process, from a signal handler.
#include <mbi/io/io.hpp>

#include <cstdio>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace mbi::io {

class AtomicFile {
 public:
  /// Opens a fresh temporary file beside `target`. Throws Error naming the target if its
  /// folder does not exist or is not writable.
  explicit AtomicFile(const std::filesystem::path& target);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// Appends bytes; throws Error on a write error.
  void write(const void* data, std::size_t bytes);
  void write(const std::string& text);
  /// Moves to an absolute byte offset (to patch a header before commit()).
  void seek(long offset);
  /// Drops everything from byte `size` on (what a failed write() left) and continues there.
  void truncate(long size);
  /// Writes the buffered bytes to the file: a full disk is reported here, not later.
  void flush();
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
  int slot_ = -1;  // in the table remove_temporaries_now() reads
};

/// Writes `target` atomically: `body` fills an AtomicFile, which is committed when it returns.
void write_file_atomic(const std::filesystem::path& target,
                       const std::function<void(AtomicFile&)>& body);
/// Writes `text` to `target` atomically.
void write_text_atomic(const std::filesystem::path& target, const std::string& text);

/// The prefix of every temporary file name of mbi.
inline constexpr const char* kTemporaryPrefix = ".mbi-tmp.";

/// Removes every temporary file this process holds open now (AtomicFile temporaries and
/// OutputSet staging files), without allocating or locking: async-signal-safe, for a handler
/// that then ends the process (_exit).
void remove_temporaries_now() noexcept;

/// Throws Error ("<what> <target>: ...") unless `target` names a file: an empty last part
/// ("dir/"), "." or ".." name a folder.
void check_file_name(const std::filesystem::path& target, const std::string& what);

/// Removes the temporary files ("<dir>/.mbi-tmp.<pid>.*") whose writing process no longer runs
/// (left by a killed process); returns how many were removed. Symbolic links are never followed.
int remove_stale_temporaries(const std::filesystem::path& dir);

/// The target a staging file of a live OutputSet stands for, else `p` itself: writers that put
/// a name into the file (a glTF's root node) take it from here, never from the staging name, so
/// the same inputs give the same bytes.
std::filesystem::path output_name(const std::filesystem::path& p);

/// The identity of an existing file (st_dev, st_ino after following symbolic links); nullopt
/// when it does not exist. Two spellings, hard links or symbolic links of one file compare equal.
struct FileId {
  unsigned long long dev = 0, ino = 0;
  bool operator==(const FileId&) const = default;
};
std::optional<FileId> file_id(const std::filesystem::path& p);

/// The outputs of one command, written all or nothing. add() reserves, before any work, a
/// staging file beside each target (created exclusively: this checks that the folder exists and
/// is writable); the command writes each output to staging(i) with the usual writers; commit()
/// renames every staging file over its target at the end. Destroyed without commit() (an error
/// on the way), it removes every staging file, and no target has been created or replaced.
///
/// Two commands never mix their outputs: add() and commit() take the lock of each target's
/// folder (FolderLock, folder_lock.hpp), waiting up to 5 s while another process holds it (a
/// commit holds it for milliseconds; a run holds its folder to the end, and is then named).
///
/// The overwrite rule of every mbi command: an existing target is refused unless `force`; a
/// target that is one of the command's inputs (by file identity: other spellings, hard links and
/// symbolic links included) or another output of the same command is refused even with `force`.
class OutputSet {
 public:
  OutputSet(std::vector<std::filesystem::path> inputs, bool force)
      : inputs_(std::move(inputs)), force_(force) {}
  ~OutputSet();
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;

  /// Checks `target` against the rule above and reserves its staging file; returns its index.
  /// `what` names the option in messages (e.g. "--stats"). Throws Error.
  /// `stem_of`: the staging name is that of output `stem_of` with target's extension (for
  /// files written together from one base name, e.g. BASE.node and BASE.ele by write_tetgen).
  std::size_t add(const std::filesystem::path& target, const std::string& what,
                  std::optional<std::size_t> stem_of = std::nullopt);
  /// Where to write output i (beside its target, same extension, a short name).
  const std::filesystem::path& staging(std::size_t i) const { return entries_.at(i).staging; }
  /// Runs body(staging(i)); an Error it throws names target(i) instead of the staging file
  /// (a full disk names the user's file, not an internal one).
  void write(std::size_t i, const std::function<void(const std::filesystem::path&)>& body) const;
  /// `what` with every staging file's name replaced by its target's (for messages).
  std::string name_targets(std::string what) const;
  const std::filesystem::path& target(std::size_t i) const { return entries_.at(i).target; }
  /// Renames every staging file over its target. Throws Error if one is missing (not written).
  void commit();

 private:
  struct Entry {
    std::filesystem::path target, staging;
    std::optional<FileId> reserved;  // the staging file as add() created it
    int slot = -1;                   // in the table remove_temporaries_now() reads
  };
  std::vector<std::filesystem::path> inputs_;
  bool force_;
  std::vector<Entry> entries_;
  bool committed_ = false;
};

}  // namespace mbi::io
