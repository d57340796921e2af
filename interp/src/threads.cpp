// Thread counts and parallel loops of mbi::interp (see threads.hpp).
#include "threads.hpp"

#include <algorithm>
#include <thread>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace mbi::interp::detail {

int all_threads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
#endif
}

int thread_count(long long work, long long min_per_thread, int requested) {
  const long long t = requested > 0 ? requested : all_threads();
  const long long cap = std::max<long long>(1, work / std::max<long long>(1, min_per_thread));
  return static_cast<int>(std::max<long long>(1, std::min(t, cap)));
}

int omp_threads(long long work, long long min_per_thread, int requested) {
#ifdef _OPENMP
  return thread_count(work, min_per_thread, requested);
#else
  (void)work, (void)min_per_thread, (void)requested;
  return 1;
#endif
}

void omp_team(int& t, int& T) {
#ifdef _OPENMP
  t = omp_get_thread_num();
  T = omp_get_num_threads();
#else
  t = 0;
  T = 1;
#endif
}

void parallel_for(long long count, int threads, const std::function<void(long long, long long)>& f) {
  if (threads <= 1 || count < 2) {
    f(0LL, count);
    return;
  }
  std::vector<std::thread> pool;
  pool.reserve(threads);
  const long long chunk = (count + threads - 1) / threads;
  for (int t = 0; t < threads; ++t) {
    const long long b = t * chunk;
    const long long e = std::min(count, b + chunk);
    if (b >= e) break;
    pool.emplace_back([&f, b, e] { f(b, e); });
  }
  for (auto& th : pool) th.join();
}

void parallel_blocks(long long count, long long block, int threads,
                     const std::function<void(long long, long long)>& f) {
  if (threads <= 1) {
    f(0LL, count);
    return;
  }
  const long long blocks = (count + block - 1) / block;
  MBI_INTERP_OMP("omp parallel for schedule(dynamic, 1) num_threads(threads)")
  for (long long b = 0; b < blocks; ++b) f(b * block, std::min(count, (b + 1) * block));
}

}  // namespace mbi::interp::detail
