#include <mbi/io/atomic_file.hpp>
#include <mbi/io/folder_lock.hpp>

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <stdio_ext.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cstring>
#include <map>
#include <mutex>
#include <random>

namespace mbi::io {
namespace {

[[noreturn]] void fail(const std::filesystem::path& target, const std::string& what) {
  throw Error(target.string() + ": " + what);
}

std::atomic<unsigned> counter{0};

// The temporaries this process holds, for remove_temporaries_now(): fixed storage that a signal
// handler reads without allocating or locking. A slot is free (0), being filled (1) or holds a
// path (2). More temporaries at once than slots are not listed (a handler leaves those behind,
// as SIGKILL would: under their temporary names).
constexpr int kSlots = 64;
struct Slot {
  std::atomic<int> state{0};
  char path[PATH_MAX];
};
Slot slots[kSlots];

int list_temporary(const std::filesystem::path& p) {
  std::error_code ec;
  const std::string abs = std::filesystem::absolute(p, ec).string();
  if (ec || abs.size() >= PATH_MAX) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int free = 0;
    if (!slots[i].state.compare_exchange_strong(free, 1)) continue;
    std::memcpy(slots[i].path, abs.c_str(), abs.size() + 1);
    slots[i].state.store(2);
    return i;
  }
  return -1;
}

void unlist_temporary(int& slot) {
  if (slot >= 0) slots[slot].state.store(0);
  slot = -1;
}

// Opens `made` exclusively (O_EXCL: never an existing file, never through a symbolic link),
// listed for remove_temporaries_now() before it exists, so that a signal at any moment finds
// it (a name listed but not yet made is harmless to unlink: it carries our process id).
// Returns the descriptor, or -1 with errno set and nothing listed.
int open_listed(const std::filesystem::path& made, int& slot) {
  slot = list_temporary(made);
  const int fd = ::open(made.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int err = errno;
    unlist_temporary(slot);
    errno = err;
  }
  return fd;
}

// "<dir>/.mbi-tmp.<pid>.<n>-<random><suffix>", created exclusively and listed (open_listed).
// Returns the open descriptor; throws naming `target`.
int create_temporary(const std::filesystem::path& target, const std::string& suffix,
                     std::filesystem::path& made, int& slot) {
  if (target.filename().empty()) fail(target, "no file name to write");
  std::filesystem::path dir = target.parent_path();
  std::error_code ec;
  if (!dir.empty() && !std::filesystem::is_directory(dir, ec)) {
    if (std::filesystem::exists(dir, ec))
      fail(target, "cannot write here: " + dir.string() + " is not a folder");
    fail(target, "folder does not exist");
  }
  if (dir.empty()) dir = ".";
  std::random_device rd;
  for (int attempt = 0; attempt < 16; ++attempt) {
    made = dir / (std::string(kTemporaryPrefix) + std::to_string(::getpid()) + "." +
                  std::to_string(counter++) + "-" + std::to_string(rd() % 1000000) + suffix);
    const int fd = open_listed(made, slot);
    if (fd >= 0) return fd;
    if (errno == EEXIST) continue;
    fail(target, std::string("cannot create a temporary file in its folder (") +
                     std::strerror(errno) + ")");
  }
  fail(target, "cannot find a free temporary file name in its folder");
}

// Staging file -> the target it stands for (output_name()).
std::mutex names_mutex;
std::map<std::string, std::filesystem::path>& staged_names() {
  static std::map<std::string, std::filesystem::path> m;
  return m;
}

// The target's extension when it is a plain short one (writers pick the format by it), else "".
std::string staging_suffix(const std::filesystem::path& target) {
  const std::string ext = target.extension().string();
  if (ext.size() < 2 || ext.size() > 16) return "";
  for (char c : ext.substr(1))
    if (!std::isalnum(static_cast<unsigned char>(c))) return "";
  return ext;
}

// How long OutputSet waits for a folder another process holds: a commit holds it for
// milliseconds, a run for its whole length.
constexpr std::chrono::seconds kCommitWait(5);

std::string errno_text() { return errno != 0 ? std::strerror(errno) : "an I/O error"; }

}  // namespace

AtomicFile::AtomicFile(const std::filesystem::path& target) : target_(target) {
  // ".mbi-tmp.<pid>.<n>-<random>.tmp": unique per process, call and attempt
  const int fd = create_temporary(target, ".tmp", temporary_, slot_);
  file_ = ::fdopen(fd, "wb");
  if (!file_) {
    ::close(fd);
    std::error_code ec;
    std::filesystem::remove(temporary_, ec);
    unlist_temporary(slot_);
    fail(target, "cannot open a temporary file in its folder");
  }
}

AtomicFile::~AtomicFile() {
  if (file_) std::fclose(file_);
  if (!committed_) {
    std::error_code ec;
    std::filesystem::remove(temporary_, ec);
  }
  unlist_temporary(slot_);
}

void AtomicFile::write(const void* data, std::size_t bytes) {
  if (!file_) fail(target_, "write after commit");
  if (bytes > 0 && std::fwrite(data, 1, bytes, file_) != bytes)
    fail(target_, "write error (" + errno_text() + ")");
}

void AtomicFile::write(const std::string& text) { write(text.data(), text.size()); }

void AtomicFile::seek(long offset) {
  if (!file_ || std::fseek(file_, offset, SEEK_SET) != 0) fail(target_, "seek error");
}

void AtomicFile::flush() {
  if (!file_) fail(target_, "flush after commit");
  if (std::fflush(file_) != 0) fail(target_, "write error (" + errno_text() + ")");
}

void AtomicFile::truncate(long size) {
  if (!file_) fail(target_, "truncate after commit");
  __fpurge(file_);  // bytes a failed write left in the buffer are dropped, not retried
  std::clearerr(file_);
  if (::ftruncate(::fileno(file_), size) != 0 || std::fseek(file_, size, SEEK_SET) != 0)
    fail(target_, "cannot drop a partly written record (" + errno_text() + ")");
}

void AtomicFile::commit() {
  if (!file_) fail(target_, "commit called twice");
  const bool bad = std::fflush(file_) != 0 || std::ferror(file_);
  const std::string why = bad ? errno_text() : "";
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (bad || rc != 0) fail(target_, "write error (" + (bad ? why : errno_text()) + ")");
  std::error_code ec;
  std::filesystem::rename(temporary_, target_, ec);
  if (ec) fail(target_, "cannot move the finished file into place: " + ec.message());
  committed_ = true;
  unlist_temporary(slot_);
}

void write_file_atomic(const std::filesystem::path& target,
                       const std::function<void(AtomicFile&)>& body) {
  AtomicFile f(target);
  body(f);
  f.commit();
}

void write_text_atomic(const std::filesystem::path& target, const std::string& text) {
  write_file_atomic(target, [&](AtomicFile& f) { f.write(text); });
}

void remove_temporaries_now() noexcept {
  for (Slot& s : slots)
    if (s.state.load() == 2) ::unlink(s.path);
}

void check_file_name(const std::filesystem::path& target, const std::string& what) {
  const std::string named = what.empty() ? target.string() : what + " " + target.string();
  const std::filesystem::path name = target.filename();
  if (name.empty() || name == "." || name == "..")
    throw Error(named + ": names a folder, not a file (give a file name, e.g. " +
                  (target / "out").string() + ")");
}

int remove_stale_temporaries(const std::filesystem::path& dir) {
  std::error_code ec;
  int removed = 0;
  const std::string prefix = kTemporaryPrefix;
  std::vector<std::filesystem::path> stale;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) != 0 || e.is_symlink(ec) || !e.is_regular_file(ec)) continue;
    const std::size_t dot = name.find('.', prefix.size());
    if (dot == std::string::npos) continue;
    long pid = 0;
    try {
      pid = std::stol(name.substr(prefix.size(), dot - prefix.size()));
    } catch (const std::exception&) {
      continue;
    }
    if (pid <= 0) continue;
    if (pid == ::getpid()) continue;                       // ours, in use
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM) continue;  // still running
    stale.push_back(e.path());
  }
  for (const auto& p : stale)
    if (std::filesystem::remove(p, ec)) ++removed;
  return removed;
}

std::optional<FileId> file_id(const std::filesystem::path& p) {
  struct stat st {};
  if (::stat(p.c_str(), &st) != 0) return std::nullopt;
  return FileId{static_cast<unsigned long long>(st.st_dev), static_cast<unsigned long long>(st.st_ino)};
}

namespace {
// The folder's identity and the file name: equal for two spellings of one (maybe absent) target.
std::optional<std::pair<FileId, std::string>> where(const std::filesystem::path& p) {
  std::filesystem::path dir = p.parent_path();
  if (dir.empty()) dir = ".";
  const auto id = file_id(dir);
  if (!id) return std::nullopt;
  return std::pair{*id, p.filename().string()};
}
const char* kind_of(std::filesystem::file_type t) {
  using T = std::filesystem::file_type;
  return t == T::fifo ? "a FIFO (named pipe)" : t == T::socket ? "a socket"
         : t == T::block ? "a block device" : t == T::character ? "a character device"
                                                                : "of another kind";
}

// A folder another process holds (a run) is refused now, not after the work.
void refuse_held_folder(const std::filesystem::path& target, const std::string& named) {
  const std::filesystem::path dir = target.parent_path().empty() ? "." : target.parent_path();
  std::error_code ec;
  try {
    if (std::filesystem::is_directory(dir, ec)) FolderLock probe(dir, kCommitWait);
  } catch (const Error& err) {
    throw Error(named + ": " + err.what());
  }
}

}  // namespace

OutputSet::~OutputSet() {
  std::error_code ec;
  const std::lock_guard<std::mutex> hold(names_mutex);
  for (Entry& e : entries_) {
    if (!committed_) std::filesystem::remove(e.staging, ec);
    unlist_temporary(e.slot);
    staged_names().erase(e.staging.string());
  }
}

std::filesystem::path output_name(const std::filesystem::path& p) {
  const std::lock_guard<std::mutex> hold(names_mutex);
  const auto it = staged_names().find(p.string());
  return it == staged_names().end() ? p : it->second;
}

std::string OutputSet::name_targets(std::string what) const {
  for (const Entry& e : entries_) {
    const std::string from = e.staging.string(), to = e.target.string();
    for (std::size_t at = what.find(from); at != std::string::npos; at = what.find(from, at + to.size()))
      what.replace(at, from.size(), to);
  }
  return what;
}

std::size_t OutputSet::add(const std::filesystem::path& target, const std::string& what,
                           std::optional<std::size_t> stem_of) {
  const std::string named = what.empty() ? target.string() : what + " " + target.string();
  check_file_name(target, what);
  std::error_code ec;
  const auto st = std::filesystem::symlink_status(target, ec);
  const bool present = !ec && std::filesystem::exists(st);
  // an input, whatever the spelling, hard link or symbolic link: never, even with --force
  if (const auto id = file_id(target)) {
    for (const auto& in : inputs_)
      if (file_id(in) == id)
        throw Error(named + ": is an input (" + in.string() +
                      "); an input is never overwritten, not even with --force");
  }
  // another output of this command
  const auto here = where(target);
  for (const Entry& e : entries_)
    if (e.target == target || (here && where(e.target) == here) ||
        (file_id(target) && file_id(target) == file_id(e.target)))
      throw Error(named + ": is also another output of this command (" + e.target.string() + ")");
  if (present) {
    if (std::filesystem::is_directory(target, ec)) throw Error(named + ": is a folder");
    // a FIFO, socket or device is refused as such: --force would not change that
    if (!std::filesystem::is_regular_file(st) && !std::filesystem::is_symlink(st))
      throw Error(named + ": exists and is not a regular file (" + kind_of(st.type()) + ")");
    if (!force_) throw Error(named + ": exists (use --force to overwrite)");
  }
  refuse_held_folder(target, named);
  Entry e;
  e.target = target;
  if (stem_of) {  // the stem's staging name with this target's extension
    const Entry& stem = entries_.at(*stem_of);
    std::string name = stem.staging.string();
    name.resize(name.size() - staging_suffix(stem.target).size());
    e.staging = name + staging_suffix(target);
    const int fd = open_listed(e.staging, e.slot);
    if (fd < 0)
      fail(target, std::string("cannot create a temporary file in its folder (") +
                       std::strerror(errno) + ")");
    ::close(fd);
  } else {
    try {
      const int fd = create_temporary(target, staging_suffix(target), e.staging, e.slot);
      ::close(fd);
    } catch (const Error& err) {
      if (what.empty()) throw;
      throw Error(what + " " + err.what());
    }
  }
  e.reserved = file_id(e.staging);  // a writer replaces the file (a new inode) or fills it
  {
    const std::lock_guard<std::mutex> hold(names_mutex);
    staged_names()[e.staging.string()] = e.target;
  }
  entries_.push_back(std::move(e));
  return entries_.size() - 1;
}

void OutputSet::write(std::size_t i, const std::function<void(const std::filesystem::path&)>& body) const {
  const Entry& e = entries_.at(i);
  try {
    body(e.staging);
  } catch (const Error& err) {
    throw Error(name_targets(err.what()));
  }
}

void OutputSet::commit() {
  if (committed_) throw Error("outputs committed twice");
  std::error_code ec;
  for (const Entry& e : entries_) {
    const bool file = std::filesystem::is_regular_file(std::filesystem::symlink_status(e.staging, ec));
    // still the empty reservation: never written (committing it would replace the target by
    // an empty file)
    const bool untouched = file && file_id(e.staging) == e.reserved && std::filesystem::file_size(e.staging, ec) == 0;
    if (!file || untouched) throw Error(e.target.string() + ": was not written");
  }
  // The folders' locks while the files move into place: two commands writing the same outputs
  // leave one's complete set, never a mix (another command's commit takes milliseconds; a run
  // holding a folder holds it for long: then this fails, naming it).
  // Locked in one order (by identity), so that two commits cannot wait on each other.
  std::vector<std::pair<FileId, std::filesystem::path>> dirs;
  for (const Entry& e : entries_) {
    const std::filesystem::path dir = e.target.parent_path().empty() ? "." : e.target.parent_path();
    if (const auto id = file_id(dir)) dirs.emplace_back(*id, dir);
  }
  std::sort(dirs.begin(), dirs.end(), [](const auto& a, const auto& b) {
    return std::pair(a.first.dev, a.first.ino) < std::pair(b.first.dev, b.first.ino);
  });
  std::vector<FolderLock> locks;
  for (std::size_t k = 0; k < dirs.size(); ++k)
    if (k == 0 || !(dirs[k].first == dirs[k - 1].first)) locks.emplace_back(dirs[k].second, kCommitWait);
  // Every output is complete before the first rename. Renames within one folder do not fail
  // for a checked target (the folder was writable at add()); they run one after another, so only
  // a change of the folders under our feet between two of them could leave some done. The
  // target's symbolic link, if any, is replaced, never followed.
  for (const Entry& e : entries_) {
    std::filesystem::rename(e.staging, e.target, ec);
    if (ec) throw Error(e.target.string() + ": cannot move the finished file into place: " + ec.message());
  }
  committed_ = true;
}

}  // namespace mbi::io
