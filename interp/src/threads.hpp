#pragma once
// How many threads a call of mbi::interp runs on, and its parallel loops (internal): the one
// place that knows the thread pool. Loops written as OpenMP pragmas use MBI_INTERP_OMP (in a
// build without OpenMP they vanish and the loop runs on the calling thread); parallel_for runs
// std::threads.
#include <functional>

#ifdef _OPENMP
#define MBI_INTERP_OMP(x) _Pragma(x)
#else
#define MBI_INTERP_OMP(x)
#endif

namespace mbi::interp::detail {

/// Every core: OpenMP's default team size, or the hardware's threads without OpenMP.
int all_threads();

/// Threads for `work` units with at least `min_per_thread` each: `requested` (> 0) or
/// all_threads(), at most work / min_per_thread, at least 1.
int thread_count(long long work, long long min_per_thread, int requested = 0);

/// thread_count() for an OpenMP region: 1 in a build without OpenMP.
int omp_threads(long long work, long long min_per_thread, int requested = 0);

/// This thread's number and the team size inside an OpenMP region (0 and 1 outside one).
void omp_team(int& t, int& T);

/// Runs f(begin, end) on [0, count) split in `threads` contiguous chunks, one std::thread each
/// (on the calling thread when threads <= 1).
void parallel_for(long long count, int threads, const std::function<void(long long, long long)>& f);

/// Runs f(begin, end) on [0, count) in blocks of `block` items, handed to `threads` OpenMP
/// threads as they free up (a core slowed by other work then holds no fixed share); one call
/// f(0, count) when threads <= 1.
void parallel_blocks(long long count, long long block, int threads,
                     const std::function<void(long long, long long)>& f);

}  // namespace mbi::interp::detail
