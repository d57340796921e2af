#pragma once
// Internal helpers of mbi::interp (not installed).
#include <mbi/interp/mesh.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <string>
#include <thread>

namespace mbi::interp::detail {

/// Throws Error unless U is n x d (d in {2,3}) and T is m x (d+1) with indices in [0, n).
/// Cheaper than validate_mesh (no degeneracy test); `who` prefixes the message.
void check_shapes(const char* who, const Eigen::Ref<const Eigen::MatrixXd>& U,
                  const Eigen::Ref<const Eigen::MatrixXi>& T);

/// Throws Error naming the first non-finite entry of A (row `what` r).
void check_finite(const char* who, const char* what, const Eigen::Ref<const Eigen::MatrixXd>& A);

/// Number of worker threads to use for `work` items (threads <= 0: hardware concurrency).
inline int thread_count(int threads, long long work, long long min_per_thread = 4096) {
  int t = threads > 0 ? threads : static_cast<int>(std::thread::hardware_concurrency());
  t = std::max(1, t);
  const long long cap = std::max<long long>(1, work / std::max<long long>(1, min_per_thread));
  return static_cast<int>(std::min<long long>(t, cap));
}

/// Runs f(begin, end) on [0, count) split in `threads` contiguous chunks.
template <typename F>
void parallel_for(long long count, int threads, F&& f) {
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

}  // namespace mbi::interp::detail
