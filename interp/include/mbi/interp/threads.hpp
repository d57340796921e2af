#pragma once
// The threads of mbi: one small pool for the whole process, shared by every object and every
// calling thread (interp's precompute, solve, Bezier points, evaluation and embedding; the frame
// pipeline, the scene runner, the viewer and the command line use them through interp).
//
//   mbi::interp::set_threads(2);   // once, before or between calls: every later call of any
//                                  // thread runs on at most 2 threads (the caller included)
//
// A call runs on the calling thread and on the pool's threads that are free at that moment; a
// pool thread that does not come at once (its core taken by another program) costs nothing: the
// calling thread shares out the work as it goes and does the rest itself. So several threads of
// a program calling mbi at once (two objects, two Python threads) share the one pool instead of
// starting teams of their own. A pool thread that has nothing to do waits on the CPU for a few
// tens of microseconds (a frame's next call then starts without a wake-up), then sleeps and
// gives the core back. Results do not depend on the thread count: every parallel loop writes
// each result from one thread in a fixed order.
//
// The precompute's sparse Cholesky factorization (CHOLMOD on the system's BLAS) runs on the
// calling thread: it asks OpenBLAS for one thread and CHOLMOD's OpenMP loops for one thread while
// it runs (docs/performance.md, "Threads").
namespace mbi::interp {

/// The most threads a count may name.
inline constexpr int kMaxThreads = 1024;

/// The one check of a thread count (set_threads and every object's threads=): throws Error
/// unless 0 <= n <= kMaxThreads; `what` names the argument in the message.
void check_threads(int n, const char* what = "threads");

/// Sets the number of threads mbi's parallel work runs on, the calling thread included, for
/// every later call from any thread: 1 runs everything on the calling thread; 0 restores the
/// default, the cores this process may run on (its CPU affinity); check_threads() refuses the
/// rest. A count
/// given to one object (FastEvaluator, pipeline::CpuEvaluator, evaluate(..., threads)) limits that
/// object's calls further; 0 there means this count. Pool threads are started when first needed
/// and kept for the life of the process.
void set_threads(int n);

/// The thread count in force (>= 1).
int threads();

/// False in a build without threads (CMake MBI_WITH_THREADS=OFF): every call then runs on the
/// calling thread and threads() is 1.
bool threads_available();

}  // namespace mbi::interp
