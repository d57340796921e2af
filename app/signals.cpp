#include "signals.hpp"

#include <mbi/io/atomic_file.hpp>

#include <signal.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>

namespace mbi::cli {
namespace {

std::atomic<int>* g_stop = nullptr;

// Only async-signal-safe calls here: atomics, write, unlink (in remove_temporaries_now), _exit.
extern "C" void on_signal(int sig) {
  if (g_stop && g_stop->load() == 0) {
    g_stop->store(sig);
    const char note[] = "\nmbi: stopping: the frame in progress is the last, then the outputs are "
                        "finished; interrupt again to stop at once\n";
    [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, note, sizeof note - 1);
    return;
  }
  io::remove_temporaries_now();
  ::_exit(128 + sig);
}

}  // namespace

void handle_interrupts(std::atomic<int>* stop) {
  g_stop = stop;
  struct sigaction sa;
  std::memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);  // one handler at a time
  sigaddset(&sa.sa_mask, SIGINT);
  sigaddset(&sa.sa_mask, SIGTERM);
  sa.sa_flags = SA_RESTART;  // reads and writes in progress go on (no EINTR failures)
  for (int sig : {SIGINT, SIGTERM}) ::sigaction(sig, &sa, nullptr);
  // a file past the size limit (ulimit -f) is a write error (EFBIG) like a full disk, whose
  // frames are kept, not a signal that kills the process with its temporaries
  ::signal(SIGXFSZ, SIG_IGN);
}

void test_signal_at(const char* stage) {
  const char* at = std::getenv("MBI_TEST_SIGNAL_AT");
  if (!at) return;
  const std::size_t n = std::strlen(stage);
  if (std::strncmp(at, stage, n) != 0) return;
  if (at[n] == '\0') ::raise(SIGINT);
  else if (std::strcmp(at + n, ":TERM") == 0) ::raise(SIGTERM);
}

}  // namespace mbi::cli
