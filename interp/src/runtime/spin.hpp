#pragma once
// Waiting on the CPU (internal): how the pool's threads and a solve's steps wait for a word to
// change before they sleep (pool.cpp) or yield their core (threads.cpp, Steps).
#include <chrono>
#include <cstdlib>
#include <thread>

namespace mbi::interp::detail {

// How long a thread without work waits on the CPU before it gives the core back: longer than the
// gaps between the calls of one frame (so that they find it running), short enough that a core
// another program wants is given back at once (docs/performance.md, "Threads", has the
// measurements). MBI_POOL_SPIN_US overrides it (for measuring).
inline std::chrono::nanoseconds spin_time() {
  static const std::chrono::nanoseconds t = [] {
    const char* v = std::getenv("MBI_POOL_SPIN_US");
    return std::chrono::nanoseconds(v && *v ? std::atoll(v) * 1000 : 50000);
  }();
  return t;
}

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__)
  asm volatile("yield");
#endif
}

/// Spins until pred() holds or spin_time() has passed; returns pred().
template <typename Pred>
bool spin_until(Pred pred) {
  if (pred()) return true;
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const auto limit = spin_time();
  for (unsigned i = 1;; ++i) {
    cpu_relax();
    if (pred()) return true;
    if ((i & 31) == 0 && Clock::now() - t0 > limit) return pred();
  }
}

/// Spins for spin_time(), then yields the core between looks, until pred() holds.
template <typename Pred>
void wait_until(Pred pred) {
  if (spin_until(pred)) return;
  while (!pred()) std::this_thread::yield();
}

}  // namespace mbi::interp::detail
