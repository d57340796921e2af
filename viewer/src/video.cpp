#include "video.hpp"

#include <mbi/gpu/window.hpp>
#include <mbi/io/io.hpp>
#include <mbi/viewer/error.hpp>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <vector>

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace mbi::viewer {
namespace fs = std::filesystem;

namespace {
// How long ffmpeg may take no frame data, and how long it may take to end after the last.
constexpr int kWriteTimeoutMs = 10000, kFinishTimeoutMs = 60000;
}  // namespace

fs::path find_ffmpeg(const fs::path& file, const std::string& what) {
  const std::string ext = io::lower_extension(file);
  if (ext != ".mp4" && ext != ".mkv" && ext != ".mov" && ext != ".webm")
    throw Error(what + " " + file.string() + ": a video is written as " + kVideoExtensions);
  const char* path = std::getenv("PATH");
  std::string_view dirs = path ? path : "/usr/bin:/bin";
  while (true) {
    const std::size_t colon = dirs.find(':');
    const fs::path candidate = fs::path(dirs.substr(0, colon).empty() ? "." : dirs.substr(0, colon)) / "ffmpeg";
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    if (colon == std::string_view::npos) break;
    dirs.remove_prefix(colon + 1);
  }
  throw Error(what + " " + file.string() +
                    ": needs ffmpeg, which is not on PATH (Debian: apt-get install ffmpeg)");
}

VideoRecorder::VideoRecorder(const fs::path& ffmpeg, const fs::path& file, std::string name, int width, int height)
    : name_(std::move(name)), width_(std::max(width & ~1, 2)), height_(std::max(height & ~1, 2)) {
  // a stopped ffmpeg must be an error of the write, not a SIGPIPE that ends the viewer
  std::signal(SIGPIPE, SIG_IGN);
  int fds[2];
  if (::pipe(fds) != 0) throw Error(name_ + ": no pipe to ffmpeg (" + std::strerror(errno) + ")");
  const std::string size = std::to_string(width_) + "x" + std::to_string(height_);
  const std::string fps = std::to_string(kVideoFps);
  std::vector<std::string> args = {"ffmpeg", "-hide_banner", "-loglevel", "error", "-y", "-f", "rawvideo",
                                   "-pix_fmt", "rgb24", "-s", size, "-r", fps, "-i", "pipe:0",
                                   "-pix_fmt", "yuv420p", file.string()};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[0], 0);
  posix_spawn_file_actions_addclose(&actions, fds[1]);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  const int rc = posix_spawn(&pid_, ffmpeg.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[0]);
  if (rc != 0) {
    ::close(fds[1]);
    pid_ = -1;
    throw Error(name_ + ": cannot start " + ffmpeg.string() + " (" + std::strerror(rc) + ")");
  }
  ::fcntl(fds[1], F_SETFD, FD_CLOEXEC);
  ::fcntl(fds[1], F_SETFL, ::fcntl(fds[1], F_GETFL) | O_NONBLOCK);  // writes wait in poll(), bounded
  pipe_ = fds[1];
}

VideoRecorder::~VideoRecorder() {
  if (pipe_ >= 0) ::close(pipe_);
  if (pid_ > 0) {
    ::kill(pid_, SIGTERM);
    ::waitpid(pid_, nullptr, 0);
  }
}

void VideoRecorder::add_frame() {
  const std::vector<std::uint8_t> rgb = gpu::read_window(width_, height_).rgb;
  size_t done = 0;
  while (done < rgb.size()) {
    const ssize_t n = ::write(pipe_, rgb.data() + done, rgb.size() - done);
    if (n > 0) {
      done += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EAGAIN) {
      // an ffmpeg that takes nothing for this long would hang the session: an error instead
      pollfd p{pipe_, POLLOUT, 0};
      const int ready = ::poll(&p, 1, kWriteTimeoutMs);
      if (ready == 0)
        throw Error(name_ + ": ffmpeg took no frame data for " + std::to_string(kWriteTimeoutMs / 1000) +
                          " s; no video written");
      if (ready > 0 || errno == EINTR) continue;
    }
    throw Error(name_ + ": ffmpeg stopped taking frames (" + std::strerror(errno) + ")");
  }
  ++frames_;
}

void VideoRecorder::finish() {
  if (pid_ <= 0) return;
  ::close(pipe_);
  pipe_ = -1;
  // ffmpeg ends once it has the end of its input; one that does not is stopped
  int status = 0;
  for (int waited = 0;; waited += 10) {
    const pid_t w = ::waitpid(pid_, &status, WNOHANG);
    if (w == pid_ || (w < 0 && errno != EINTR)) break;
    if (waited >= kFinishTimeoutMs) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status, 0);
      pid_ = -1;
      throw Error(name_ + ": ffmpeg did not end " + std::to_string(kFinishTimeoutMs / 1000) +
                        " s after the last frame; no video written");
    }
    ::usleep(10000);
  }
  pid_ = -1;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw Error(name_ + ": ffmpeg failed (" +
                      (WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                         : std::string("killed by a signal")) + "); no video written");
}

std::string VideoRecorder::describe() const {
  return name_ + ": " + std::to_string(width_) + " x " + std::to_string(height_) + " at " + std::to_string(kVideoFps) +
         " fps";
}

}  // namespace mbi::viewer
