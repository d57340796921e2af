// Evaluation of embedded points from element Bezier control points (facts 5, 6).
#include <mbi/interp/evaluate.hpp>

#include "method/detail.hpp"
#include "evaluate/evaluate_float.hpp"
#include "runtime/threads.hpp"

#include <array>
#include <atomic>
#include <cmath>
#include <string>
#include <type_traits>

namespace mbi::interp {
namespace {

template <typename Scalar>
using MatX = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;

// Checks B / emb consistency (elements too, unless `elements` is false); returns d.
int check_inputs(const MatrixIn& B, const Embedding& emb, bool elements = true) {
  const int d = static_cast<int>(B.cols());
  if (d != 2 && d != 3) throw Error("Bezier points must have 2 or 3 columns");
  const int K = (d + 1) * (d + 2) / 2;
  if (B.rows() % K != 0)
    throw Error("Bezier points have " + std::to_string(B.rows()) +
                " rows, not a multiple of " + std::to_string(K));
  if (emb.bary.cols() != d + 1 || emb.bary.rows() != emb.element.size())
    throw Error("embedding has " + std::to_string(emb.bary.cols()) +
                " coordinates per point, expected " + std::to_string(d + 1));
  if (!elements) return d;
  // the first point whose element is out of range, looked for on the library's threads
  const long long m = B.rows() / K, p = emb.size();
  std::atomic<long long> bad{p};
  detail::parallel_blocks(p, 1 << 16, detail::thread_count(p, 1 << 16), [&](long long b, long long e) {
    for (long long i = b; i < e; ++i)
      if (emb.element(i) < 0 || emb.element(i) >= m) {
        for (long long cur = bad.load(); i < cur && !bad.compare_exchange_weak(cur, i);) {
        }
        return;
      }
  });
  if (const long long i = bad.load(); i < p)
    throw Error("point " + std::to_string(i) + " refers to element " +
                std::to_string(emb.element(i)) + " outside [0, " + std::to_string(m) + ")");
  return d;
}

// Position and derivatives dx/dphi_k (k = 0..D) of the quadratic Bezier simplex.
// P: an element's K control points, point k's coordinate c at P[k is + c os].
template <int D, typename Scalar>
inline void bezier_eval(const Scalar* P, std::ptrdiff_t is, std::ptrdiff_t os, const Scalar* b, Scalar* x,
                        Scalar (*g)[D]) {
  constexpr int E = D * (D + 1) / 2;
  static constexpr std::array<std::pair<int, int>, 6> edges3{
      {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};
  static constexpr std::array<std::pair<int, int>, 3> edges2{{{0, 1}, {0, 2}, {1, 2}}};
  for (int c = 0; c < D; ++c) x[c] = 0;
  for (int k = 0; k <= D; ++k) {
    const Scalar w = b[k] * b[k];
    for (int c = 0; c < D; ++c) x[c] += w * P[k * is + c * os];
    if (g)
      for (int c = 0; c < D; ++c) g[k][c] = 2 * b[k] * P[k * is + c * os];
  }
  for (int s = 0; s < E; ++s) {
    const int i = D == 3 ? edges3[s].first : edges2[s].first;
    const int j = D == 3 ? edges3[s].second : edges2[s].second;
    const Scalar* q = P + (D + 1 + s) * is;
    const Scalar w = 2 * b[i] * b[j];
    for (int c = 0; c < D; ++c) x[c] += w * q[c * os];
    if (g)
      for (int c = 0; c < D; ++c) {
        g[i][c] += 2 * b[j] * q[c * os];
        g[j][c] += 2 * b[i] * q[c * os];
      }
  }
}

// Points: the control points, point r's coordinate c at Points[r is + c os].
template <int D, typename Scalar>
void kernel(const Scalar* Points, std::ptrdiff_t is, std::ptrdiff_t os, const Embedding& emb,
            const MatX<Scalar>* grads /* D x (m (D+1)) */, const ConstPointsRef<Scalar>* normals_rest,
            PointsRef<Scalar>& pos, PointsRef<Scalar>* normals_out, int threads) {
  constexpr int K = (D + 1) * (D + 2) / 2;
  const long long np = emb.size();
  detail::parallel_blocks(np, 8192, detail::thread_count(np, 8192, threads), [&](long long begin, long long end) {
    Scalar b[D + 1], x[D], g[D + 1][D];
    for (long long p = begin; p < end; ++p) {
      const int e = emb.element(p);
      for (int k = 0; k <= D; ++k) b[k] = static_cast<Scalar>(emb.bary(p, k));
      const Scalar* P = Points + static_cast<std::ptrdiff_t>(e) * K * is;
      if (!normals_out) {
        bezier_eval<D, Scalar>(P, is, os, b, x, nullptr);
        for (int c = 0; c < D; ++c) pos(p, c) = x[c];
        continue;
      }
      bezier_eval<D, Scalar>(P, is, os, b, x, g);
      for (int c = 0; c < D; ++c) pos(p, c) = x[c];
      // J = sum_k g_k a_k^T (column r of J: sum_k g_k a_k[r])
      Scalar J[D][D];
      const Scalar* a = grads->data() + static_cast<long long>(e) * (D + 1) * D;
      for (int c = 0; c < D; ++c)
        for (int r = 0; r < D; ++r) {
          Scalar s = 0;
          for (int k = 0; k <= D; ++k) s += g[k][c] * a[k * D + r];
          J[c][r] = s;
        }
      Scalar n[D];
      for (int c = 0; c < D; ++c) n[c] = (*normals_rest)(p, c);
      Scalar o[D];
      if constexpr (D == 3) {
        // cof(J) has columns j1 x j2, j2 x j0, j0 x j1 (j_r = column r of J)
        Scalar C[3][3];
        for (int r = 0; r < 3; ++r) {
          const int r1 = (r + 1) % 3, r2 = (r + 2) % 3;
          C[0][r] = J[1][r1] * J[2][r2] - J[2][r1] * J[1][r2];
          C[1][r] = J[2][r1] * J[0][r2] - J[0][r1] * J[2][r2];
          C[2][r] = J[0][r1] * J[1][r2] - J[1][r1] * J[0][r2];
        }
        for (int c = 0; c < 3; ++c) o[c] = C[c][0] * n[0] + C[c][1] * n[1] + C[c][2] * n[2];
      } else {
        // cof([[a, b], [c, d]]) = [[d, -c], [-b, a]]
        o[0] = J[1][1] * n[0] - J[1][0] * n[1];
        o[1] = -J[0][1] * n[0] + J[0][0] * n[1];
      }
      Scalar len = 0;
      for (int c = 0; c < D; ++c) len += o[c] * o[c];
      len = std::sqrt(len);
      for (int c = 0; c < D; ++c) (*normals_out)(p, c) = len > 0 ? o[c] / len : Scalar(0);
    }
  });
}

// Checks B and emb, and for normals (normals_rest given) the basis gradients and the rest
// normals; returns d. Everything is checked before an output is touched, except the points'
// elements when the kernels check them as they go (elements_later: the float path).
template <typename Scalar>
int check_all(const MatrixIn& B, const Embedding& emb, const ConstPointsRef<Scalar>* normals_rest,
              bool elements_later = false) {
  const int d = check_inputs(B, emb, !elements_later);
  if (normals_rest) {
    const long long m = B.rows() / ((d + 1) * (d + 2) / 2);
    if (emb.gradients.rows() != m * (d + 1) || emb.gradients.cols() != d)
      throw Error("normals need the embedding's basis gradients (" + std::to_string(m * (d + 1)) +
                  " x " + std::to_string(d) + ", filled by embed()), got " +
                  std::to_string(emb.gradients.rows()) + " x " + std::to_string(emb.gradients.cols()));
    if (normals_rest->rows() != emb.size() || normals_rest->cols() != d)
      throw Error("rest normals must be " + std::to_string(emb.size()) + " x " +
                  std::to_string(d) + ", got " + std::to_string(normals_rest->rows()) + " x " +
                  std::to_string(normals_rest->cols()));
  }
  return d;
}

void check_output(const char* what, Eigen::Index rows, Eigen::Index cols, const Embedding& emb, int d) {
  if (rows != emb.size() || cols != d)
    throw Error(std::string(what) + " must be " + std::to_string(emb.size()) + " x " +
                std::to_string(d) + ", got " + std::to_string(rows) + " x " + std::to_string(cols));
}

// Float positions in 3D into memory of unit inner stride run on FastEvaluator's kernels (the
// double path keeps the Bernstein form).
template <typename Scalar>
bool float_path(const MatrixIn& B, Eigen::Index inner_stride, bool normals) {
  return std::is_same_v<Scalar, float> && !normals && B.cols() == 3 && inner_stride == 1;
}

// Inputs checked by check_all, outputs p x d.
template <typename Scalar>
void run(const MatrixIn& B, const Embedding& emb, int d, const ConstPointsRef<Scalar>* normals_rest,
         PointsRef<Scalar> positions, PointsRef<Scalar>* normals_out, int threads) {
  if constexpr (std::is_same_v<Scalar, float>) {
    if (float_path<Scalar>(B, positions.innerStride(), normals_out != nullptr))
      return detail::evaluate_float3(B, emb, positions, threads);
  }
  // double control points are read where they are, in any layout; float ones converted once into
  // D x (m K) (each element's points contiguous), kept per thread so that a frame loop allocates nothing
  thread_local MatX<Scalar> Prow, grads;
  const Scalar* points = nullptr;
  std::ptrdiff_t is = d, os = 1;
  if constexpr (std::is_same_v<Scalar, double>) {
    points = B.data(), is = B.innerStride(), os = B.outerStride();
  } else {
    Prow = B.transpose().template cast<Scalar>();
    points = Prow.data();
  }
  if (normals_out) grads = emb.gradients.transpose().template cast<Scalar>();
  const MatX<Scalar>* g = normals_out ? &grads : nullptr;
  if (d == 3) kernel<3, Scalar>(points, is, os, emb, g, normals_rest, positions, normals_out, threads);
  else kernel<2, Scalar>(points, is, os, emb, g, normals_rest, positions, normals_out, threads);
}

// The listed points' positions, row i from points[i]: the full kernel's arithmetic (bezier_eval).
template <int D>
void subset_kernel(const MatrixIn& B, const Embedding& emb, std::span<const Eigen::Index> points,
                   PointsRef<double>& pos, int threads) {
  constexpr int K = (D + 1) * (D + 2) / 2;
  const std::ptrdiff_t is = B.innerStride(), os = B.outerStride();
  const long long n = static_cast<long long>(points.size());
  detail::parallel_blocks(n, 2048, detail::thread_count(n, 2048, threads), [&](long long begin, long long end) {
    double b[D + 1], x[D];
    for (long long i = begin; i < end; ++i) {
      const Eigen::Index p = points[static_cast<size_t>(i)];
      for (int k = 0; k <= D; ++k) b[k] = emb.bary(p, k);
      bezier_eval<D, double>(B.data() + static_cast<std::ptrdiff_t>(emb.element(p)) * K * is, is, os, b, x, nullptr);
      for (int c = 0; c < D; ++c) pos(i, c) = x[c];
    }
  });
}

}  // namespace

void evaluate(const MatrixIn& B, const Embedding& emb, std::span<const Eigen::Index> points,
              PointsRef<double> positions, int threads) {
  const int d = check_inputs(B, emb, false);
  const long long m = B.rows() / ((d + 1) * (d + 2) / 2);
  detail::check_point_list(emb, points, m);
  if (positions.rows() != static_cast<Eigen::Index>(points.size()) || positions.cols() != d)
    throw Error("positions must be " + std::to_string(points.size()) + " x " + std::to_string(d) + ", got " +
                std::to_string(positions.rows()) + " x " + std::to_string(positions.cols()));
  if (d == 3) subset_kernel<3>(B, emb, points, positions, threads);
  else subset_kernel<2>(B, emb, points, positions, threads);
}

template <typename Scalar>
void evaluate(const MatrixIn& B, const Embedding& emb,
              Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>& positions, int threads) {
  const int d = check_all<Scalar>(B, emb, nullptr, float_path<Scalar>(B, 1, false));
  positions.resize(emb.size(), d);
  run<Scalar>(B, emb, d, nullptr, positions, nullptr, threads);
}

template <typename Scalar>
void evaluate(const MatrixIn& B, const Embedding& emb,
              const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>& normals_rest,
              Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>& positions,
              Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>& normals_out, int threads) {
  const ConstPointsRef<Scalar> rest(normals_rest);
  const int d = check_all<Scalar>(B, emb, &rest);
  normals_out.resize(emb.size(), d);
  positions.resize(emb.size(), d);
  PointsRef<Scalar> normals(normals_out);
  run<Scalar>(B, emb, d, &rest, positions, &normals, threads);
}

template <typename Scalar>
void evaluate(const MatrixIn& B, const Embedding& emb, PointsRef<Scalar> positions, int threads) {
  const int d = check_all<Scalar>(B, emb, nullptr, float_path<Scalar>(B, positions.innerStride(), false));
  check_output("positions", positions.rows(), positions.cols(), emb, d);
  run<Scalar>(B, emb, d, nullptr, positions, nullptr, threads);
}

template <typename Scalar>
void evaluate(const MatrixIn& B, const Embedding& emb,
              const ConstPointsRef<Scalar>& normals_rest, PointsRef<Scalar> positions,
              PointsRef<Scalar> normals_out, int threads) {
  const int d = check_all<Scalar>(B, emb, &normals_rest);
  check_output("positions", positions.rows(), positions.cols(), emb, d);
  check_output("normals", normals_out.rows(), normals_out.cols(), emb, d);
  run<Scalar>(B, emb, d, &normals_rest, positions, &normals_out, threads);
}

template void evaluate<float>(const MatrixIn&, const Embedding&, Eigen::MatrixXf&, int);
template void evaluate<double>(const MatrixIn&, const Embedding&, Eigen::MatrixXd&, int);
template void evaluate<float>(const MatrixIn&, const Embedding&, const Eigen::MatrixXf&,
                              Eigen::MatrixXf&, Eigen::MatrixXf&, int);
template void evaluate<double>(const MatrixIn&, const Embedding&, const Eigen::MatrixXd&,
                               Eigen::MatrixXd&, Eigen::MatrixXd&, int);
template void evaluate<float>(const MatrixIn&, const Embedding&, PointsRef<float>, int);
template void evaluate<double>(const MatrixIn&, const Embedding&, PointsRef<double>, int);
template void evaluate<float>(const MatrixIn&, const Embedding&, const ConstPointsRef<float>&,
                              PointsRef<float>, PointsRef<float>, int);
template void evaluate<double>(const MatrixIn&, const Embedding&, const ConstPointsRef<double>&,
                               PointsRef<double>, PointsRef<double>, int);

Eigen::MatrixXd jacobian(const Eigen::Ref<const Eigen::MatrixXd>& U,
                         const Eigen::Ref<const Eigen::MatrixXi>& T, const BezierPoints& B, int e,
                         const Eigen::Ref<const Eigen::VectorXd>& bary) {
  const Eigen::MatrixXd A = basis_gradients(U, T, e);  // checks shapes and e
  const int d = static_cast<int>(U.cols());
  const int K = (d + 1) * (d + 2) / 2;
  if (B.cols() != d || B.rows() != T.rows() * K)
    throw Error("Bezier points must be " + std::to_string(T.rows() * K) + " x " + std::to_string(d));
  if (bary.size() != d + 1) throw Error("bary must have " + std::to_string(d + 1) + " entries");
  // g_k = dx/dphi_k = 2 phi_k x_k + sum_{edges (k, j)} 2 phi_j P_kj
  Eigen::MatrixXd g(d, d + 1);
  for (int k = 0; k <= d; ++k) g.col(k) = 2 * bary(k) * B.row(e * K + k).transpose();
  const auto& edges = bezier_edges(d);
  for (size_t s = 0; s < edges.size(); ++s) {
    const auto [i, j] = edges[s];
    const Eigen::VectorXd q = B.row(e * K + d + 1 + static_cast<int>(s)).transpose();
    g.col(i) += 2 * bary(j) * q;
    g.col(j) += 2 * bary(i) * q;
  }
  return g * A;  // sum_k g_k a_k^T
}

}  // namespace mbi::interp
