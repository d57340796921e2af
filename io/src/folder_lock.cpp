#include <mbi/io/folder_lock.hpp>
#include <mbi/io/io.hpp>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

namespace mbi::io {
namespace {

// The command line of process `pid`, its arguments joined by spaces ("" when unreadable).
std::string command_line(const std::string& pid) {
  std::ifstream in("/proc/" + pid + "/cmdline", std::ios::binary);
  std::string raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  while (!raw.empty() && raw.back() == '\0') raw.pop_back();
  for (char& c : raw)
    if (c == '\0') c = ' ';
    else if (static_cast<unsigned char>(c) < 0x20) c = '?';
  if (raw.size() > 200) raw = raw.substr(0, 200) + "...";
  return raw;
}

}  // namespace

std::string folder_lock_holder(const std::filesystem::path& dir) {
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0) return "";
  char want[64];
  std::snprintf(want, sizeof want, "%02x:%02x:%llu", major(st.st_dev), minor(st.st_dev),
                static_cast<unsigned long long>(st.st_ino));
  // "1: FLOCK  ADVISORY  WRITE 1234 08:01:5678 0 EOF" (a waiter has "->" after the number)
  std::ifstream in("/proc/locks");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string x; words >> x;)
      if (x != "->") w.push_back(x);
    if (w.size() < 6 || w[1] != "FLOCK" || w[5] != want) continue;
    if (line.find("->") != std::string::npos) continue;  // a waiter, not the holder
    const std::string cmd = command_line(w[4]);
    return "process " + w[4] + (cmd.empty() ? "" : ": " + cmd);
  }
  return "";
}

FolderLock::FolderLock(const std::filesystem::path& dir, std::chrono::milliseconds wait) {
  const std::filesystem::path shown = dir.empty() ? "." : dir;
  fd_ = ::open(shown.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0)
    throw Error(shown.string() + ": cannot open this folder to lock it (" + std::strerror(errno) + ")");
  const auto until = std::chrono::steady_clock::now() + wait;
  for (;;) {
    if (::flock(fd_, LOCK_EX | LOCK_NB) == 0) return;
    const int err = errno;
    if (err == EWOULDBLOCK && std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      continue;
    }
    ::close(fd_);
    fd_ = -1;
    if (err != EWOULDBLOCK)
      throw Error(shown.string() + ": cannot lock this folder (" + std::strerror(err) + ")");
    const std::string holder = folder_lock_holder(shown);
    throw Error(shown.string() + ": another process is writing into this folder (" +
                  (holder.empty() ? "which one is not known" : holder) +
                  "); wait until it ends, or choose another folder");
  }
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the only descriptor releases the lock
}

}  // namespace mbi::io
