#include <mbi/io/atomic_file.hpp>

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <random>

namespace mbi::io {
namespace {

[[noreturn]] void fail(const std::filesystem::path& target, const std::string& what) {
  throw IoError(target.string() + ": " + what);
}

}  // namespace

AtomicFile::AtomicFile(const std::filesystem::path& target) : target_(target) {
  static std::atomic<unsigned> counter{0};
  if (target.filename().empty()) fail(target, "no file name to write");
  std::filesystem::path dir = target.parent_path();
  std::error_code ec;
  if (!dir.empty() && !std::filesystem::is_directory(dir, ec)) fail(target, "folder does not exist");
  if (dir.empty()) dir = ".";
  std::random_device rd;
  for (int attempt = 0; attempt < 16 && !file_; ++attempt) {
    // ".<name>.<pid>-<counter>-<random>.tmp": unique per process, call and attempt; O_EXCL
    // guarantees that no existing file (a user's, or a symlink) is opened.
    temporary_ = dir / ("." + target.filename().string() + "." + std::to_string(::getpid()) + "-" +
                        std::to_string(counter++) + "-" + std::to_string(rd() % 1000000) + ".tmp");
    const int fd = ::open(temporary_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0) {
      if (errno == EEXIST) continue;
      fail(target, std::string("cannot create a temporary file in its folder (") +
                       std::strerror(errno) + ")");
    }
    file_ = ::fdopen(fd, "wb");
    if (!file_) {
      ::close(fd);
      std::filesystem::remove(temporary_, ec);
      fail(target, "cannot open a temporary file in its folder");
    }
  }
  if (!file_) fail(target, "cannot find a free temporary file name in its folder");
}

AtomicFile::~AtomicFile() {
  if (file_) std::fclose(file_);
  if (!committed_) {
    std::error_code ec;
    std::filesystem::remove(temporary_, ec);
  }
}

void AtomicFile::write(const void* data, std::size_t bytes) {
  if (!file_) fail(target_, "write after commit");
  if (bytes > 0 && std::fwrite(data, 1, bytes, file_) != bytes) fail(target_, "write error");
}

void AtomicFile::write(const std::string& text) { write(text.data(), text.size()); }

void AtomicFile::seek(long offset) {
  if (!file_ || std::fseek(file_, offset, SEEK_SET) != 0) fail(target_, "seek error");
}

void AtomicFile::commit() {
  if (!file_) fail(target_, "commit called twice");
  const bool bad = std::fflush(file_) != 0 || std::ferror(file_);
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (bad || rc != 0) fail(target_, "write error");
  std::error_code ec;
  std::filesystem::rename(temporary_, target_, ec);
  if (ec) fail(target_, "cannot move the finished file into place: " + ec.message());
  committed_ = true;
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

}  // namespace mbi::io
