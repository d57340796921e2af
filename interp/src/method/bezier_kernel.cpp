// The Bezier points of each element from X (and modified-BI's M): the per-frame loop of
// bezier_points() and bezier_bi(), with the dimension fixed at compile time and the elements
// shared out over the library's threads (each element's rows are written by one thread only).
#include "method/detail.hpp"
#include "runtime/threads.hpp"

#include <array>

namespace mbi::interp::detail {
namespace {

// The vertex pairs of bezier_edges(D), fixed at compile time.
template <int D>
constexpr auto kEdges = [] {
  std::array<std::array<int, 2>, D * (D + 1) / 2> e{};
  int s = 0;
  for (int i = 0; i <= D; ++i)
    for (int j = i + 1; j <= D; ++j) e[static_cast<size_t>(s++)] = {i, j};
  return e;
}();

template <int D, class XIn, class MIn, class Out>
void rows_of(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
             const XIn& X, const MIn* M, Out& B, const int* list, long long e0, long long e1) {
  constexpr int K = (D + 1) * (D + 2) / 2;
  for (long long at = e0; at < e1; ++at) {
    const long long e = list ? list[at] : at;
    // each vertex's x, u and M_i read once into locals (the strided matrices may alias B, so the
    // compiler would reload them for every edge)
    double x[D + 1][D], u[D + 1][D] = {}, m[D + 1][D][D] = {};
    for (int k = 0; k <= D; ++k) {
      const int v = T(e, k);
      for (int c = 0; c < D; ++c) x[k][c] = X(v, c);
      if (!M) continue;
      for (int c = 0; c < D; ++c) u[k][c] = U(v, c);
      for (int r = 0; r < D; ++r)
        for (int c = 0; c < D; ++c) m[k][c][r] = (*M)(v * D + c, r);
    }
    for (int k = 0; k <= D; ++k)
      for (int c = 0; c < D; ++c) B(e * K + k, c) = x[k][c];
    for (size_t s = 0; s < kEdges<D>.size(); ++s) {
      const int i = kEdges<D>[s][0], j = kEdges<D>[s][1];
      for (int c = 0; c < D; ++c) {
        // P_ij = (x_i + x_j)/2 + (M_i - M_j)(u_j - u_i)/2  (fact 5; M = 0 for BI)
        double p = x[i][c] + x[j][c];
        for (int r = 0; r < D; ++r) p += (m[i][c][r] - m[j][c][r]) * (u[j][r] - u[i][r]);
        B(e * K + D + 1 + static_cast<long long>(s), c) = 0.5 * p;
      }
    }
  }
}

}  // namespace

void bezier_rows(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                 const Eigen::Ref<const Eigen::MatrixXd>& X, const MatrixIn* M, MatrixOut B,
                 std::span<const int> elements, bool listed) {
  const long long m = listed ? static_cast<long long>(elements.size()) : T.rows();
  const int* list = listed ? elements.data() : nullptr;
  const int d = static_cast<int>(X.cols());
  // contiguous columns (the usual MatrixXd) get their inner strides fixed at 1 at compile time
  const bool packed = B.innerStride() == 1 && (!M || M->innerStride() == 1);
  parallel_blocks(m, 256, thread_count(m, 512), [&](long long e0, long long e1) {
    if (!packed) {
      if (d == 3) rows_of<3>(U, T, X, M, B, list, e0, e1);
      else rows_of<2>(U, T, X, M, B, list, e0, e1);
      return;
    }
    using In = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>;
    Eigen::Map<Eigen::MatrixXd, 0, Eigen::OuterStride<>> Bp(B.data(), B.rows(), B.cols(), {B.outerStride()});
    const In Xp(X.data(), X.rows(), X.cols(), {X.outerStride()});
    const In Mp(M ? M->data() : X.data(), M ? M->rows() : 0, M ? M->cols() : 0, {M ? M->outerStride() : 0});
    if (d == 3) rows_of<3>(U, T, Xp, M ? &Mp : nullptr, Bp, list, e0, e1);
    else rows_of<2>(U, T, Xp, M ? &Mp : nullptr, Bp, list, e0, e1);
  });
}

}  // namespace mbi::interp::detail
