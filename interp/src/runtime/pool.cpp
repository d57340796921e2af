// The process's one pool of threads (see pool.hpp).
#include "runtime/pool.hpp"

#include "runtime/spin.hpp"

#ifdef MBI_WITH_THREADS

#include <algorithm>
#include <exception>

#ifdef __linux__
#include <linux/futex.h>
#include <sched.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace mbi::interp::detail {
namespace {

// Sleeping until a 32-bit word changes (futex on Linux; elsewhere C++20 atomic wait).
void sleep_while(std::atomic<std::uint32_t>& word, std::uint32_t value) {
#ifdef __linux__
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAIT_PRIVATE, value, nullptr, nullptr, 0);
#else
  word.wait(value);
#endif
}

void wake(std::atomic<std::uint32_t>& word) {
#ifdef __linux__
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAKE_PRIVATE, 1 << 30, nullptr, nullptr, 0);
#else
  word.notify_all();
#endif
}

// True on pool threads, and on a caller while it runs its own body: a nested call runs alone.
thread_local bool t_in_body = false;

constexpr std::uint32_t kSleeping = 1u << 31;  // Job::done: the caller sleeps on it

}  // namespace

struct Pool::Job {
  const FunctionRef<void()>* body = nullptr;
  std::atomic<std::uint32_t> done{0};  // threads that finished body, | kSleeping
  std::mutex error_m;
  std::exception_ptr error;
};

struct Pool::Worker {
  alignas(64) std::atomic<Job*> job{nullptr};  // posted, not yet picked up
  std::atomic<std::uint32_t> posts{0};         // bumped by every post: what the thread waits on
  std::atomic<std::uint32_t> sleeping{0};
  std::thread thread;
};

Pool& Pool::get() {
  // never destroyed: its threads sleep until the process ends
  static Pool* pool = new Pool;
  return *pool;
}

int Pool::cores() {
  static const int n = [] {
#ifdef __linux__
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
#endif
    return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  }();
  return n;
}

int Pool::acquire(int n, Worker** out) {
  std::lock_guard<std::mutex> lock(m_);
  // start threads on demand, up to the count this call asks for (the pool never holds more
  // threads than the largest count asked for, less one: the caller)
  while (static_cast<int>(idle_.size()) < n && static_cast<int>(workers_.size()) < n) {
    workers_.push_back(std::make_unique<Worker>());
    Worker* w = workers_.back().get();
    w->thread = std::thread([this, w] { work(*w); });
    w->thread.detach();
    idle_.push_back(w);
  }
  const int k = std::min<int>(n, static_cast<int>(idle_.size()));
  for (int i = 0; i < k; ++i) {
    out[i] = idle_.back();
    idle_.pop_back();
  }
  return k;
}

void Pool::release(Worker* const* w, int n) {
  std::lock_guard<std::mutex> lock(m_);
  for (int i = 0; i < n; ++i) idle_.push_back(w[i]);
}

void Pool::work(Worker& w) {
  t_in_body = true;
  std::uint32_t seen = 0;
  for (;;) {
    if (!spin_until([&] { return w.posts.load(std::memory_order_acquire) != seen; })) {
      // Dekker with run(): it bumps posts, then reads sleeping; we set sleeping, then read posts
      w.sleeping.store(1, std::memory_order_seq_cst);
      while (w.posts.load(std::memory_order_seq_cst) == seen) sleep_while(w.posts, seen);
      w.sleeping.store(0, std::memory_order_relaxed);
    }
    seen = w.posts.load(std::memory_order_acquire);
    Job* j = w.job.exchange(nullptr, std::memory_order_acq_rel);
    if (!j) continue;  // taken back before we came
    try {
      (*j->body)();
    } catch (...) {
      std::lock_guard<std::mutex> lock(j->error_m);
      if (!j->error) j->error = std::current_exception();
    }
    // the last touch of *j: the caller may return as soon as the count is complete (a wake-up
    // on its address then reaches at most a later waiter there, which rechecks its word)
    if (j->done.fetch_add(1, std::memory_order_acq_rel) & kSleeping) wake(j->done);
  }
}

void Pool::run(int threads, FunctionRef<void()> body) {
  constexpr int kMax = 256;
  if (threads <= 1 || t_in_body) {
    body();
    return;
  }
  Worker* w[kMax];
  const int n = acquire(std::min(threads - 1, kMax), w);
  if (n == 0) {
    body();
    return;
  }
  Job job;
  job.body = &body;
  for (int i = 0; i < n; ++i) {
    w[i]->job.store(&job, std::memory_order_release);
    w[i]->posts.fetch_add(1, std::memory_order_seq_cst);
    if (w[i]->sleeping.load(std::memory_order_seq_cst)) wake(w[i]->posts);
  }
  std::exception_ptr mine;
  t_in_body = true;
  try {
    body();
  } catch (...) {
    mine = std::current_exception();
  }
  t_in_body = false;
  // take back the posts not picked up yet; wait for the threads that did pick theirs up
  std::uint32_t started = 0;
  for (int i = 0; i < n; ++i)
    if (w[i]->job.exchange(nullptr, std::memory_order_acq_rel) != &job) ++started;
  auto finished = [&] { return (job.done.load(std::memory_order_acquire) & ~kSleeping) == started; };
#ifdef __linux__
  if (!spin_until(finished)) {
    for (std::uint32_t v = job.done.load(std::memory_order_acquire); (v & ~kSleeping) != started;
         v = job.done.load(std::memory_order_acquire)) {
      if (!(v & kSleeping) && !job.done.compare_exchange_weak(v, v | kSleeping)) continue;
      sleep_while(job.done, v | kSleeping);
    }
  }
#else
  wait_until(finished);  // never asleep on a word a thread may touch after we return
#endif
  release(w, n);
  if (mine) std::rethrow_exception(mine);
  if (job.error) std::rethrow_exception(job.error);
}

}  // namespace mbi::interp::detail

#endif  // MBI_WITH_THREADS
