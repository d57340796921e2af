#pragma once
// OpenMP helpers of mbi::interp (internal). Without OpenMP everything runs on the calling thread.
#include <algorithm>

#ifdef _OPENMP
#include <omp.h>
#define MBI_INTERP_OMP(x) _Pragma(x)
#else
#define MBI_INTERP_OMP(x)
#endif

namespace mbi::interp::detail {

/// Team size for `work` units with at least `min_per_thread` each (1 without OpenMP).
inline int omp_threads(long long work, long long min_per_thread) {
#ifdef _OPENMP
  const long long cap = std::max<long long>(1, work / std::max<long long>(1, min_per_thread));
  return static_cast<int>(std::max<long long>(1, std::min<long long>(omp_get_max_threads(), cap)));
#else
  (void)work;
  (void)min_per_thread;
  return 1;
#endif
}

/// This thread's number and the team size inside a parallel region (0, 1 outside).
inline void omp_team(int& t, int& T) {
#ifdef _OPENMP
  t = omp_get_thread_num();
  T = omp_get_num_threads();
#else
  t = 0;
  T = 1;
#endif
}

}  // namespace mbi::interp::detail
