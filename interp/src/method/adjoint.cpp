// Transposes of evaluate() and bezier_points() (see adjoint.hpp).
#include <mbi/interp/adjoint.hpp>

#include "method/detail.hpp"
#include "runtime/threads.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace mbi::interp {
namespace {

// Adds point p's Bernstein weights times g (D values) into its element's K x D block A (row-major).
template <int D>
void scatter_point(const Embedding& emb, Eigen::Index p, const double* g, double* A) {
  constexpr int K = (D + 1) * (D + 2) / 2;
  static constexpr std::array<std::pair<int, int>, 6> edges3{{{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};
  static constexpr std::array<std::pair<int, int>, 3> edges2{{{0, 1}, {0, 2}, {1, 2}}};
  double b[D + 1];
  for (int k = 0; k <= D; ++k) b[k] = emb.bary(p, k);
  for (int k = 0; k <= D; ++k) {
    const double w = b[k] * b[k];
    for (int c = 0; c < D; ++c) A[k * D + c] += w * g[c];
  }
  for (int s = 0; s < K - D - 1; ++s) {
    const auto [i, j] = D == 3 ? edges3[s] : edges2[s];
    const double w = 2 * b[i] * b[j];
    for (int c = 0; c < D; ++c) A[(D + 1 + s) * D + c] += w * g[c];
  }
}

// Adds each point's Bernstein weights times its row of G into its element's K x D block of acc
// (row-major, element after element), for the points [begin, end).
template <int D>
void scatter(const Embedding& emb, const ConstPointsRef<double>& G, long long begin, long long end, double* acc) {
  constexpr int K = (D + 1) * (D + 2) / 2;
  for (long long p = begin; p < end; ++p) {
    double g[D];
    for (int c = 0; c < D; ++c) g[c] = G(p, c);
    scatter_point<D>(emb, p, g, acc + static_cast<long long>(emb.element(p)) * K * D);
  }
}

// Sums rows [runs[r], runs[r + 1]) of G (points[i]'s row i) into part r's K x D block, for r in [r0, r1).
template <int D>
void scatter_runs(const Embedding& emb, std::span<const Eigen::Index> points, const ConstPointsRef<double>& G,
                  const std::vector<long long>& runs, long long r0, long long r1, double* part) {
  constexpr int K = (D + 1) * (D + 2) / 2;
  for (long long r = r0; r < r1; ++r) {
    double* A = part + r * K * D;
    std::fill(A, A + K * D, 0.0);
    for (long long i = runs[static_cast<size_t>(r)]; i < runs[static_cast<size_t>(r) + 1]; ++i) {
      double g[D];
      for (int c = 0; c < D; ++c) g[c] = G(i, c);
      scatter_point<D>(emb, points[static_cast<size_t>(i)], g, A);
    }
  }
}

// The first row of G that is not finite (-1: none).
long long first_non_finite(const ConstPointsRef<double>& G) {
  for (Eigen::Index p = 0; p < G.rows(); ++p)
    for (Eigen::Index c = 0; c < G.cols(); ++c)
      if (!std::isfinite(G(p, c))) return p;
  return -1;
}

void check_out(const char* what, Eigen::Index rows, Eigen::Index cols, Eigen::Index want_rows, Eigen::Index want_cols) {
  if (rows != want_rows || cols != want_cols)
    throw Error(std::string(what) + " must be " + std::to_string(want_rows) + " x " + std::to_string(want_cols) +
                ", got " + std::to_string(rows) + " x " + std::to_string(cols));
}

}  // namespace

BezierPoints evaluate_transpose(const Embedding& emb, const ConstPointsRef<double>& G, int elements, int threads) {
  const int d = emb.dim();
  if (d != 2 && d != 3) throw Error("the embedding must be 2D or 3D");
  BezierPoints out(static_cast<Eigen::Index>(std::max(elements, 0)) * ((d + 1) * (d + 2) / 2), d);
  evaluate_transpose(emb, G, elements, out, threads);
  return out;
}

void evaluate_transpose(const Embedding& emb, const ConstPointsRef<double>& G, int elements,
                        Eigen::Ref<BezierPoints> out, int threads) {
  const int d = emb.dim();
  if (d != 2 && d != 3) throw Error("the embedding must be 2D or 3D");
  if (G.rows() != emb.size() || G.cols() != d)
    throw Error("dL/dpositions must be " + std::to_string(emb.size()) + " x " + std::to_string(d) +
                ", got " + std::to_string(G.rows()) + " x " + std::to_string(G.cols()));
  if (elements < 0) throw Error("elements must be >= 0");
  for (Eigen::Index p = 0; p < emb.size(); ++p)
    if (emb.element(p) < 0 || emb.element(p) >= elements)
      throw Error("point " + std::to_string(p) + " refers to element " + std::to_string(emb.element(p)) +
                  " outside [0, " + std::to_string(elements) + ")");
  const int K = (d + 1) * (d + 2) / 2;
  check_out("dL/dB", out.rows(), out.cols(), static_cast<Eigen::Index>(elements) * K, d);
  const long long block = static_cast<long long>(elements) * K * d;
  // one accumulator a thread (no two threads add into the same memory), summed in thread order;
  // kept per calling thread, so that a frame loop allocates nothing
  const long long np = emb.size();
  const int nt = detail::thread_count(np, 16384, threads);
  thread_local std::vector<double> acc;
  acc.assign(static_cast<size_t>(nt * block), 0.0);
  double* accp = acc.data();
  const long long chunk = (np + nt - 1) / nt;
  detail::parallel_blocks(nt, 1, nt, [&](long long t0, long long t1) {
    for (long long t = t0; t < t1; ++t) {
      const long long begin = t * chunk, end = std::min(np, begin + chunk);
      if (begin >= end) continue;
      if (d == 3) scatter<3>(emb, G, begin, end, accp + t * block);
      else scatter<2>(emb, G, begin, end, accp + t * block);
    }
  });
  bool finite = true;
  for (Eigen::Index r = 0; r < out.rows(); ++r)
    for (int c = 0; c < d; ++c) {
      double s = 0;
      for (int t = 0; t < nt; ++t) s += acc[static_cast<size_t>(t * block + r * d + c)];
      out(r, c) = s;
      finite = finite && std::isfinite(s);
    }
  // a NaN or infinity in G reaches its element's sums whatever its weights (0 * inf is NaN)
  if (!finite) {
    const long long p = first_non_finite(G);
    throw Error(p >= 0 ? "dL/dpositions row " + std::to_string(p) + " has a non-finite value"
                       : std::string("dL/dpositions is too large: its sums overflow"));
  }
}

void evaluate_transpose(const Embedding& emb, std::span<const Eigen::Index> points, const ConstPointsRef<double>& G,
                        int elements, Eigen::Ref<BezierPoints> out, int threads) {
  const int d = emb.dim();
  if (d != 2 && d != 3) throw Error("the embedding must be 2D or 3D");
  if (G.rows() != static_cast<Eigen::Index>(points.size()) || G.cols() != d)
    throw Error("dL/dpositions must be " + std::to_string(points.size()) + " x " + std::to_string(d) +
                ", got " + std::to_string(G.rows()) + " x " + std::to_string(G.cols()));
  if (elements < 0) throw Error("elements must be >= 0");
  const int K = (d + 1) * (d + 2) / 2;
  check_out("dL/dB", out.rows(), out.cols(), static_cast<Eigen::Index>(elements) * K, d);
  // runs of consecutive points of one element, each summed on one thread, then added in order
  thread_local std::vector<long long> runs;
  runs.clear();
  detail::check_point_list(emb, points, elements);
  for (size_t i = 0; i < points.size(); ++i)
    if (i == 0 || emb.element(points[i]) != emb.element(points[i - 1])) runs.push_back(static_cast<long long>(i));
  const long long nr = static_cast<long long>(runs.size());
  runs.push_back(static_cast<long long>(points.size()));
  thread_local std::vector<double> part;
  part.resize(static_cast<size_t>(nr * K * d));
  // the calling thread's scratch, named here: in the lambda a thread_local would be the pool thread's own
  const std::vector<long long>& starts = runs;
  double* partp = part.data();
  detail::parallel_blocks(nr, 16, detail::thread_count(nr, 16, threads), [&](long long r0, long long r1) {
    if (d == 3) scatter_runs<3>(emb, points, G, starts, r0, r1, partp);
    else scatter_runs<2>(emb, points, G, starts, r0, r1, partp);
  });
  // only the runs' elements' rows: the others are not the transpose's to write (adjoint.hpp)
  auto first_row = [&](long long r) {
    return static_cast<Eigen::Index>(emb.element(points[static_cast<size_t>(runs[static_cast<size_t>(r)])])) * K;
  };
  for (long long r = 0; r < nr; ++r) out.middleRows(first_row(r), K).setZero();
  bool finite = true;
  for (long long r = 0; r < nr; ++r) {
    const Eigen::Index first = first_row(r);
    for (int k = 0; k < K; ++k)
      for (int c = 0; c < d; ++c) {
        out(first + k, c) += partp[(r * K + k) * d + c];
        finite = finite && std::isfinite(out(first + k, c));
      }
  }
  if (!finite) {
    const long long p = first_non_finite(G);
    throw Error(p >= 0 ? "dL/dpositions row " + std::to_string(p) + " has a non-finite value"
                       : std::string("dL/dpositions is too large: its sums overflow"));
  }
}

BezierTranspose bezier_transpose(const Eigen::Ref<const Eigen::MatrixXd>& U,
                                 const Eigen::Ref<const Eigen::MatrixXi>& T, const BezierPoints& G) {
  BezierTranspose out{Eigen::MatrixXd(U.rows(), U.cols()), VertexMatrices(U.rows() * U.cols(), U.cols())};
  bezier_transpose(U, T, G, out.X, out.M);
  return out;
}

namespace {
// Checks the transpose's shapes and zeroes X and M.
void start_bezier_transpose(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                            const Eigen::Ref<const BezierPoints>& G, Eigen::Ref<Eigen::MatrixXd> X,
                            Eigen::Ref<VertexMatrices> M) {
  detail::check_shapes(U, T);
  const int d = static_cast<int>(U.cols());
  const int n = static_cast<int>(U.rows());
  const int K = (d + 1) * (d + 2) / 2;
  if (G.rows() != T.rows() * K || G.cols() != d)
    throw Error("dL/dB must be " + std::to_string(T.rows() * K) + " x " + std::to_string(d) + ", got " +
                std::to_string(G.rows()) + " x " + std::to_string(G.cols()));
  check_out("dL/dX", X.rows(), X.cols(), n, d);
  check_out("dL/dM", M.rows(), M.cols(), static_cast<Eigen::Index>(n) * d, d);
  X.setZero();
  M.setZero();
}

// Adds element e's part of the transpose: its K rows of G to X and M.
void add_bezier_transpose(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                          const Eigen::Ref<const BezierPoints>& G, Eigen::Index e, Eigen::Ref<Eigen::MatrixXd> X,
                          Eigen::Ref<VertexMatrices> M) {
  const int d = static_cast<int>(U.cols());
  const int K = (d + 1) * (d + 2) / 2;
  const auto& edges = bezier_edges(d);
  for (int k = 0; k <= d; ++k) X.row(T(e, k)) += G.row(e * K + k);
  for (size_t s = 0; s < edges.size(); ++s) {
    const int i = T(e, edges[s].first), j = T(e, edges[s].second);
    // P_ij = (x_i + x_j)/2 + (M_i - M_j)(u_j - u_i)/2  (fact 5)
    for (int c = 0; c < d; ++c) {
      const double g = 0.5 * G(e * K + d + 1 + static_cast<Eigen::Index>(s), c);
      X(i, c) += g;
      X(j, c) += g;
      for (int r = 0; r < d; ++r) {
        const double v = g * (U(j, r) - U(i, r));
        M(i * d + c, r) += v;
        M(j * d + c, r) -= v;
      }
    }
  }
}
}  // namespace

void bezier_transpose(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                      const Eigen::Ref<const BezierPoints>& G, Eigen::Ref<Eigen::MatrixXd> X,
                      Eigen::Ref<VertexMatrices> M) {
  start_bezier_transpose(U, T, G, X, M);
  for (Eigen::Index e = 0; e < T.rows(); ++e) add_bezier_transpose(U, T, G, e, X, M);
}

void bezier_transpose(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                      const Eigen::Ref<const BezierPoints>& G, std::span<const int> elements,
                      Eigen::Ref<Eigen::MatrixXd> X, Eigen::Ref<VertexMatrices> M) {
  start_bezier_transpose(U, T, G, X, M);
  detail::check_index_list("elements", elements, T.rows());
  for (int e : elements) add_bezier_transpose(U, T, G, e, X, M);
}

}  // namespace mbi::interp
