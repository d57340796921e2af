// The pool and the parallel loops of mbi::interp (see threads.hpp and mbi/interp/threads.hpp).
#include "runtime/threads.hpp"

#include "runtime/spin.hpp"

#include <mbi/interp/mesh.hpp>
#include <mbi/interp/threads.hpp>

#include <algorithm>
#include <exception>
#include <mutex>
#include <string>

#ifdef MBI_WITH_THREADS
#include "runtime/pool.hpp"
#endif

#if defined(__linux__) || defined(__APPLE__)
#include <dlfcn.h>
#define MBI_INTERP_DLSYM 1
#endif

namespace mbi::interp {

namespace {
std::atomic<int> g_threads{0};  // 0: the default
}

void check_threads(int n, const char* what) {
  if (n < 0 || n > kMaxThreads)
    throw Error(std::string(what) + " must be a whole number from 0 (the cores this process may run on) to " +
                std::to_string(kMaxThreads) + ", got " + std::to_string(n));
}

void set_threads(int n) {
  check_threads(n);
  g_threads.store(n, std::memory_order_relaxed);
}

int threads() {
#ifdef MBI_WITH_THREADS
  const int n = g_threads.load(std::memory_order_relaxed);
  return n > 0 ? n : detail::Pool::cores();
#else
  return 1;
#endif
}

bool threads_available() {
#ifdef MBI_WITH_THREADS
  return true;
#else
  return false;
#endif
}

}  // namespace mbi::interp

namespace mbi::interp::detail {

int all_threads() { return interp::threads(); }

int thread_count(long long work, long long min_per_thread, int requested) {
  const long long lib = all_threads();
  const long long t = requested > 0 ? std::min<long long>(requested, lib) : lib;
  const long long cap = std::max<long long>(1, work / std::max<long long>(1, min_per_thread));
  return static_cast<int>(std::max<long long>(1, std::min(t, cap)));
}

void run_shared(int threads, FunctionRef<void()> body) {
#ifdef MBI_WITH_THREADS
  Pool::get().run(threads, body);
#else
  (void)threads;
  body();
#endif
}

void parallel_blocks(long long count, long long block, int threads, FunctionRef<void(long long, long long)> f) {
  if (threads <= 1 || count <= block) {
    f(0LL, count);
    return;
  }
  Blocks blocks(count, block);
  run_shared(std::min<long long>(threads, (count + block - 1) / block), [&] {
    for (long long b, e; blocks.next(b, e);) f(b, e);
  });
}

// ---------------------------------------------------------------- steps

namespace {
constexpr std::uint64_t kHalf = (std::uint64_t(1) << 20) - 1;  // blocks taken from one end
std::uint64_t tag_of(std::uint64_t step) { return (step >> 1) & ((std::uint64_t(1) << 24) - 1); }
}  // namespace

bool Steps::take(std::uint64_t tag, long long count, long long block, bool front, long long& begin, long long& end) {
  const long long blocks = (count + block - 1) / block;
  std::uint64_t v = claim_.load(std::memory_order_relaxed);
  for (;;) {
    const long long f = static_cast<long long>(v & kHalf), k = static_cast<long long>((v >> 20) & kHalf);
    if ((v >> kShift) != tag || f + k >= blocks) return false;
    const std::uint64_t next = front ? v + 1 : v + (std::uint64_t(1) << 20);
    if (claim_.compare_exchange_weak(v, next, std::memory_order_acq_rel)) {
      const long long i = front ? f : blocks - 1 - k;
      begin = i * block;
      end = begin + block < count ? begin + block : count;
      return true;
    }
  }
}

void Steps::work(std::uint64_t tag, const Fn* fn, long long count, long long block, bool front) {
  for (long long b, e; take(tag, count, block, front, b, e);) {
    (*fn)(b, e);
    done_.fetch_add(e - b, std::memory_order_release);
  }
}

void Steps::run(long long count, long long block, Fn fn) {
  // a seqlock: the step number is odd while the step's fields are written
  block = std::max(block > 0 ? block : 1, (count + static_cast<long long>(kHalf) - 1) / static_cast<long long>(kHalf));
  const std::uint64_t s = step_.load(std::memory_order_relaxed);
  step_.store(s + 1, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  fn_.store(&fn, std::memory_order_relaxed);
  count_.store(count, std::memory_order_relaxed);
  block_.store(block, std::memory_order_relaxed);
  done_.store(0, std::memory_order_relaxed);
  claim_.store(tag_of(s + 2) << kShift, std::memory_order_relaxed);
  step_.store(s + 2, std::memory_order_release);
  work(tag_of(s + 2), &fn, count, block, true);
  wait_until([&] { return done_.load(std::memory_order_acquire) >= count; });
}

void Steps::close() { step_.store(kClosed, std::memory_order_release); }

void Steps::join() {
  std::uint64_t last = 0;  // published steps are even and >= 2
  for (;;) {
    std::uint64_t s = 0;
    wait_until([&] {
      s = step_.load(std::memory_order_acquire);
      return s == kClosed || (s != last && !(s & 1));
    });
    if (s == kClosed) return;
    const Fn* fn = fn_.load(std::memory_order_relaxed);
    const long long count = count_.load(std::memory_order_relaxed), block = block_.load(std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_acquire);
    if (step_.load(std::memory_order_relaxed) != s) continue;  // rewritten while read
    work(tag_of(s), fn, count, block, false);
    last = s;
  }
}

// ---------------------------------------------------------------- foreign pools

namespace {

template <typename F>
F lookup(const char* name) {
#ifdef MBI_INTERP_DLSYM
  return reinterpret_cast<F>(dlsym(RTLD_DEFAULT, name));
#else
  (void)name;
  return nullptr;
#endif
}

struct Foreign {
  using GetInt = int (*)();
  using SetInt = void (*)(int);
  GetInt blas_get = lookup<GetInt>("openblas_get_num_threads");
  SetInt blas_set = lookup<SetInt>("openblas_set_num_threads");
  GetInt omp_get_max = lookup<GetInt>("omp_get_max_threads");
  SetInt omp_set_num = lookup<SetInt>("omp_set_num_threads");
  GetInt omp_get_dyn = lookup<GetInt>("omp_get_dynamic");
  SetInt omp_set_dyn = lookup<SetInt>("omp_set_dynamic");
  std::mutex m;
  int guards = 0, blas_saved = 0;  // guards alive, and OpenBLAS's count before the first
};

Foreign& foreign() {
  static Foreign f;
  return f;
}

}  // namespace

SerialForeignPools::SerialForeignPools(int blas_threads) : blas_threads_(std::max(1, blas_threads)) {
  Foreign& f = foreign();
  if (f.blas_get && f.blas_set) {
    std::lock_guard<std::mutex> lock(f.m);
    if (f.guards++ == 0) {
      f.blas_saved = f.blas_get();
      if (f.blas_saved != blas_threads_) f.blas_set(blas_threads_);
    }
  }
  // OpenMP's nthreads-var and dyn-var belong to the calling thread: with dynamic threads on and
  // one thread asked for, even a loop that names its thread count (CHOLMOD's name 4) runs on one.
  if (f.omp_get_max && f.omp_set_num && f.omp_get_dyn && f.omp_set_dyn) {
    omp_threads_ = f.omp_get_max();
    omp_dynamic_ = f.omp_get_dyn();
    f.omp_set_num(1);
    f.omp_set_dyn(1);
  }
}

SerialForeignPools::~SerialForeignPools() {
  Foreign& f = foreign();
  if (omp_threads_ > 0) {
    f.omp_set_num(omp_threads_);
    f.omp_set_dyn(omp_dynamic_);
  }
  if (f.blas_get && f.blas_set) {
    std::lock_guard<std::mutex> lock(f.m);
    if (--f.guards == 0 && f.blas_saved != blas_threads_) f.blas_set(f.blas_saved);
  }
}

}  // namespace mbi::interp::detail
