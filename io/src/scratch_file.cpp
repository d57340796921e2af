#include <mbi/io/atomic_file.hpp>
#include <mbi/io/io.hpp>
#include <mbi/io/scratch_file.hpp>

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <random>

namespace mbi::io {
namespace {

std::string errno_text() { return errno != 0 ? std::strerror(errno) : "an I/O error"; }

// An unnamed file in `dir`: O_TMPFILE where the file system has it, else a temporary name
// created exclusively and unlinked at once.
int unnamed_file(const std::filesystem::path& dir, const std::string& what) {
  const int fd = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
  if (fd >= 0) return fd;
  std::random_device rd;
  for (int attempt = 0; attempt < 16; ++attempt) {
    const std::filesystem::path p = dir / (std::string(kTemporaryPrefix) + std::to_string(::getpid()) +
                                           ".scratch-" + std::to_string(rd() % 1000000));
    const int named = ::open(p.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (named >= 0) {
      ::unlink(p.c_str());
      return named;
    }
    if (errno != EEXIST) break;
  }
  throw Error(what + ": cannot make a scratch file in " + dir.string() + " (" + errno_text() + ")");
}

}  // namespace

ScratchFile::ScratchFile(const std::filesystem::path& dir, std::string what)
    : fd_(unnamed_file(dir.empty() ? "." : dir, what)), what_(std::move(what)) {}

ScratchFile::~ScratchFile() {
  if (fd_ >= 0) ::close(fd_);
}

void ScratchFile::append(const void* data, std::size_t bytes) {
  const char* p = static_cast<const char*>(data);
  std::size_t done = 0;
  while (done < bytes) {
    const ssize_t n = ::pwrite(fd_, p + done, bytes - done, size_ + static_cast<long>(done));
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    const std::string why = n == 0 ? "nothing written" : errno_text();
    // the partial record goes (shortening needs no space); reads never go past size_ anyway
    [[maybe_unused]] const int ignored = ::ftruncate(fd_, size_);
    throw Error(what_ + ": write error in its scratch file (" + why + ")");
  }
  size_ += static_cast<long>(bytes);
}

void ScratchFile::truncate(long size) {
  if (size < 0 || size > size_) throw Error(what_ + ": truncate past the end of its scratch file");
  if (::ftruncate(fd_, size) != 0)
    throw Error(what_ + ": cannot shorten its scratch file (" + errno_text() + ")");
  size_ = size;
}

void ScratchFile::read(long offset, void* data, std::size_t bytes) const {
  if (offset < 0 || offset + static_cast<long>(bytes) > size_)
    throw Error(what_ + ": read past the end of its scratch file");
  char* p = static_cast<char*>(data);
  std::size_t done = 0;
  while (done < bytes) {
    const ssize_t n = ::pread(fd_, p + done, bytes - done, offset + static_cast<long>(done));
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    throw Error(what_ + ": read error in its scratch file (" + (n == 0 ? "end of file" : errno_text()) + ")");
  }
}

}  // namespace mbi::io
