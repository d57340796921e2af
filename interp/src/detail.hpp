#pragma once
// Internal helpers of mbi::interp (not installed).
#include <mbi/interp/mesh.hpp>

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <algorithm>
#include <string>
#include <thread>
#include <vector>

namespace mbi::interp::detail {

/// Throws Error unless U is n x d (d in {2,3}) and T is m x (d+1) with indices in [0, n).
/// Cheaper than validate_mesh (no degeneracy test); `who` prefixes the message.
void check_shapes(const char* who, const Eigen::Ref<const Eigen::MatrixXd>& U,
                  const Eigen::Ref<const Eigen::MatrixXi>& T);

/// Throws Error naming the first non-finite entry of A (row `what` r).
void check_finite(const char* who, const char* what, const Eigen::Ref<const Eigen::MatrixXd>& A);

/// Per-component quadratic forms (method.md facts 1-3), unweighted, energy = z^T H z:
/// vibr_mm (dn x dn), disc_mm (dn x dn), disc_mx (dn x n), disc_xx (n x n); m index i d + r.
struct Hessians {
  Eigen::SparseMatrix<double> vibr_mm, disc_mm, disc_mx, disc_xx;
};
Hessians assemble(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T);

/// Gauge treatment (fact 4). free_vertex(i) = 1 when m_i are unknowns. Returns, per full m
/// index (i d + r), 1 when that unknown must be pinned to zero to remove the gauge null space
/// (t + S u_i on every face-connected component, restricted to what the fixed vertices leave);
/// null_dim receives the number of removed null vectors.
std::vector<char> gauge_pins(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T,
                             const std::vector<char>& free_vertex, int& null_dim);

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
