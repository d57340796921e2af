#pragma once
// The simulator's node loops in fixed blocks, and its system matrix in full block rows for products.
//
// Every loop here runs over fixed blocks of nodes; each block writes outputs of its own and sums
// are kept per block and added in block order, so the results do not depend on which thread ran
// which block, nor on whether a parallel loop is set at all.
#include <mbi/sim/simulator.hpp>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <functional>
#include <vector>

namespace mbi::sim::detail {

/// f(begin, end) for the blocks [k block, min((k + 1) block, count)) of [0, count): on `loop`
/// when it is set and there is more than one block, else in order on this thread.
template <typename F>
void for_blocks(const ParallelFor& loop, long long count, long long block, F&& f) {
  if (count <= 0) return;
  if (loop && count > block) {
    loop(count, block, std::function<void(long long, long long)>(std::ref(f)));  // no copy of f
    return;
  }
  for (long long b = 0; b < count; b += block) f(b, std::min(b + block, count));
}

/// S sums over [0, count): f(begin, end) returns a block's sums (std::array<double, S>); they
/// are added in block order.
template <int S, typename F>
std::array<double, S> sum_blocks(const ParallelFor& loop, long long count, long long block, F&& f) {
  constexpr size_t kOnStack = 64;  // blocks whose sums need no allocation
  const size_t blocks = static_cast<size_t>((count + block - 1) / block);
  std::array<std::array<double, S>, kOnStack> stack;
  std::vector<std::array<double, S>> heap(blocks > kOnStack ? blocks : 0);
  std::array<double, S>* part = blocks > kOnStack ? heap.data() : stack.data();
  for_blocks(loop, count, block, [&](long long b, long long e) { part[static_cast<size_t>(b / block)] = f(b, e); });
  std::array<double, S> total{};
  for (size_t k = 0; k < blocks; ++k)
    for (int i = 0; i < S; ++i) total[i] += part[k][i];
  return total;
}

/// A symmetric matrix of 3x3 node blocks kept in full rows (both triangles), from the simulator's
/// lower blocks: column j holds blocks [outer[j], outer[j + 1]), the diagonal first, then the
/// rows row[p] > j. Each row of a product is summed in column order by one thread.
class BlockRows {
 public:
  /// The pattern of the lower blocks (n + 1 column starts, row of each block).
  void build(const std::vector<int>& outer, const std::vector<int>& row);
  /// Copies the values of the lower blocks (column-major 3x3) into both triangles.
  void gather(const std::vector<Eigen::Matrix3d>& lower, const ParallelFor& loop);
  /// y = A x (3n each); returns x . y when `dot`, else 0.
  double multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y, bool dot, const ParallelFor& loop) const;

  static constexpr long long kNodes = 32;  // nodes per block of the node loops

 private:
  // y's rows [b, e) (nodes); returns x . y over them
  double multiply_rows(const double* x, double* y, long long b, long long e) const;
  std::vector<int> start_, col_;  // row i: blocks [start_[i], start_[i + 1]), column col_[p]
  std::vector<int> source_;       // lower block of each full block, ~index when its transpose
  std::vector<double> value_;     // 9 a block, column-major
};

}  // namespace mbi::sim::detail
