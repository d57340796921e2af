#include "block_rows.hpp"

#include <algorithm>

namespace mbi::sim::detail {

void BlockRows::build(const std::vector<int>& outer, const std::vector<int>& row) {
  const int n = static_cast<int>(outer.size()) - 1;
  // each node's row: the blocks (i, j) stored in column j < i, its diagonal, then the transposes
  // of its column's blocks (j, i) with j > i; in ascending column order
  std::vector<std::vector<int>> rows(static_cast<size_t>(n));
  for (int j = 0; j < n; ++j)
    for (int p = outer[j] + 1; p < outer[j + 1]; ++p) rows[static_cast<size_t>(row[p])].push_back(p);
  start_.assign(static_cast<size_t>(n) + 1, 0);
  col_.clear();
  source_.clear();
  for (int i = 0; i < n; ++i) {
    for (int p : rows[static_cast<size_t>(i)]) {
      const auto j = std::upper_bound(outer.begin(), outer.end(), p) - outer.begin() - 1;
      col_.push_back(static_cast<int>(j));
      source_.push_back(p);
    }
    for (int p = outer[i]; p < outer[i + 1]; ++p) {
      col_.push_back(row[p]);
      source_.push_back(p == outer[i] ? p : ~p);
    }
    start_[static_cast<size_t>(i) + 1] = static_cast<int>(col_.size());
  }
  value_.assign(9 * col_.size(), 0.0);
}

void BlockRows::gather(const std::vector<Eigen::Matrix3d>& lower, const ParallelFor& loop) {
  const long long n = static_cast<long long>(start_.size()) - 1;
  for_blocks(loop, n, kNodes, [&](long long b, long long e) {
    for (int p = start_[static_cast<size_t>(b)]; p < start_[static_cast<size_t>(e)]; ++p) {
      const int s = source_[static_cast<size_t>(p)];
      Eigen::Map<Eigen::Matrix3d> out(value_.data() + 9 * static_cast<size_t>(p));
      if (s >= 0) out = lower[static_cast<size_t>(s)];
      else out = lower[static_cast<size_t>(~s)].transpose();
    }
  });
}

double BlockRows::multiply_rows(const double* x, double* y, long long b, long long e) const {
  using Pair = Eigen::Vector2d;
  using PairIn = Eigen::Map<const Pair, Eigen::Unaligned>;
  double dot = 0.0;
  for (long long i = b; i < e; ++i) {
    // rows 0 and 1 of the blocks as one pair, row 2 alone: each the same sum per row
    Pair top = Pair::Zero();
    double last = 0.0;
    for (int p = start_[static_cast<size_t>(i)]; p < start_[static_cast<size_t>(i) + 1]; ++p) {
      const double* a = value_.data() + 9 * static_cast<size_t>(p);
      const double* xc = x + 3 * static_cast<size_t>(col_[static_cast<size_t>(p)]);
      top += PairIn(a) * xc[0] + PairIn(a + 3) * xc[1] + PairIn(a + 6) * xc[2];
      last += a[2] * xc[0] + a[5] * xc[1] + a[8] * xc[2];
    }
    double* yi = y + 3 * i;
    yi[0] = top[0];
    yi[1] = top[1];
    yi[2] = last;
    dot += x[3 * i] * yi[0] + x[3 * i + 1] * yi[1] + x[3 * i + 2] * yi[2];
  }
  return dot;
}

double BlockRows::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y, bool dot, const ParallelFor& loop) const {
  const long long n = static_cast<long long>(start_.size()) - 1;
  y.resize(3 * n);
  const std::array<double, 1> s = sum_blocks<1>(loop, n, kNodes, [&](long long b, long long e) {
    return std::array<double, 1>{multiply_rows(x.data(), y.data(), b, e)};
  });
  return dot ? s[0] : 0.0;
}

}  // namespace mbi::sim::detail
