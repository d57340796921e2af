#pragma once
// The parallel loops of mbi::interp (internal) and the one pool they run on (public side:
// mbi/interp/threads.hpp). Work is shared, never split in fixed parts: the calling thread starts
// at once and takes blocks of work from a counter, and each pool thread takes blocks from the same
// counter when it arrives. A pool thread whose core is busy elsewhere therefore delays nothing
// (the caller does its blocks), which a fixed split with a barrier cannot give. Every loop writes
// each result from one block, in an order that does not depend on who ran the block, so results
// are the same for every thread count. In a build without threads (MBI_WITH_THREADS=OFF) every
// loop runs on the calling thread.
#include <atomic>
#include <cstdint>
#include <memory>
#include <type_traits>
#include <utility>

namespace mbi::interp::detail {

/// A callable passed down without a copy or an allocation (the loops below take lambdas).
template <typename Sig>
class FunctionRef;
template <typename R, typename... A>
class FunctionRef<R(A...)> {
 public:
  template <typename F, typename = std::enable_if_t<!std::is_same_v<std::decay_t<F>, FunctionRef>>>
  FunctionRef(F&& f)  // NOLINT: implicit, as std::function
      : obj_(const_cast<void*>(static_cast<const void*>(std::addressof(f)))),
        call_([](void* o, A... a) -> R { return (*static_cast<std::remove_reference_t<F>*>(o))(std::forward<A>(a)...); }) {}
  R operator()(A... a) const { return call_(obj_, std::forward<A>(a)...); }

 private:
  void* obj_;
  R (*call_)(void*, A...);
};

/// The library's thread count (interp::threads()).
int all_threads();

/// Threads for `work` units with at least `min_per_thread` each: `requested` (> 0; at most the
/// library's count) or the library's count, at most work / min_per_thread, at least 1.
int thread_count(long long work, long long min_per_thread, int requested = 0);

/// [0, count) handed out in blocks of `block` (the last one shorter), to whichever thread asks.
class Blocks {
 public:
  Blocks(long long count, long long block) : count_(count), block_(block > 0 ? block : 1) {}
  /// The next block [begin, end); false when none is left.
  bool next(long long& begin, long long& end) {
    const long long b = next_.fetch_add(block_, std::memory_order_relaxed);
    if (b >= count_) return false;
    begin = b;
    end = b + block_ < count_ ? b + block_ : count_;
    return true;
  }
  long long count() const { return count_; }

 private:
  long long count_, block_;
  alignas(64) std::atomic<long long> next_{0};
};

/// Runs body() on the calling thread and on up to threads - 1 pool threads, each at most once,
/// as they come; body shares its work out through counters (Blocks). Returns when every thread
/// that started body has returned from it; rethrows the first exception one of them threw.
/// Inside body (on any of its threads) a nested call runs on that thread alone.
void run_shared(int threads, FunctionRef<void()> body);

/// f(begin, end) for the blocks of [0, count) of `block` items, on up to `threads` threads;
/// one call f(0, count) when threads <= 1 or count <= block.
void parallel_blocks(long long count, long long block, int threads, FunctionRef<void(long long, long long)> f);

/// Work in consecutive steps inside one run_shared job (a solve's sweeps): the caller publishes a
/// step (run), every thread of the job takes blocks of it, and run returns once all its blocks are
/// done, so the next step may read what this one wrote. Between steps the caller may work alone.
/// The caller calls run and close; every other thread of the job calls join, which takes blocks
/// of each step until close (spinning between steps, then yielding its core). The caller takes
/// blocks from the front, the others from the back: with two threads each keeps about the same
/// part of every step, and of the data it touches, in its own cache from step to step.
class Steps {
 public:
  using Fn = FunctionRef<void(long long, long long)>;
  /// Caller: fn over [0, count) in blocks of `block`, on every thread in the job.
  void run(long long count, long long block, Fn fn);
  /// Caller: no more steps.
  void close();
  /// The other threads of the job.
  void join();

 private:
  // claim word: step tag (high 24 bits), then the blocks taken from the back and from the front
  // (20 bits each), so that a thread late for one step can never take a block of the next under
  // the old step's function
  static constexpr int kShift = 40;
  static constexpr std::uint64_t kClosed = ~std::uint64_t(0);
  bool take(std::uint64_t tag, long long count, long long block, bool front, long long& begin, long long& end);
  void work(std::uint64_t tag, const Fn* fn, long long count, long long block, bool front);

  alignas(64) std::atomic<std::uint64_t> claim_{0};
  alignas(64) std::atomic<long long> done_{0};
  alignas(64) std::atomic<std::uint64_t> step_{0};  // even: published (odd: being written); kClosed
  std::atomic<const Fn*> fn_{nullptr};
  std::atomic<long long> count_{0}, block_{1};
};

/// While alive, BLAS (OpenBLAS, when it is the system's BLAS) runs on blas_threads threads and
/// the OpenMP loops of libraries the calling thread calls into (CHOLMOD's) on one: the
/// precompute's factorization is serial unless it is large, so neither library leaves threads
/// spinning after a small one. OpenBLAS's count is process-wide: it is set by the first guard and
/// given back by the last one alive (a BLAS call from another thread meanwhile runs on that count
/// too). OpenMP's settings are the calling thread's own. Both are looked up at run time (dlsym),
/// so nothing here depends on either library.
class SerialForeignPools {
 public:
  explicit SerialForeignPools(int blas_threads = 1);
  ~SerialForeignPools();
  SerialForeignPools(const SerialForeignPools&) = delete;
  SerialForeignPools& operator=(const SerialForeignPools&) = delete;

 private:
  int omp_threads_ = 0, omp_dynamic_ = 0;
  int blas_threads_ = 1;
};

}  // namespace mbi::interp::detail
