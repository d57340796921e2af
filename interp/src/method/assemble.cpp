// Modified-BI's quadratic forms (method.md facts 1-3): E_vibr per element and E_disc per interior
// face, their local Hessians computed on the library's threads a block at a time and added into
// the matrices in element / face order on the calling thread, so that the sums are the same
// whatever the thread count.
#include "method/detail.hpp"
#include "runtime/threads.hpp"

#include <mbi/error.hpp>
#include <mbi/interp/mesh.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace mbi::interp::detail {

namespace {

using SpMat = Eigen::SparseMatrix<double>;

// Which vertices couple in a Hessian: for each vertex j its neighbours (j included), sorted,
// nb[start[j] .. start[j + 1]). Built from groups of vertices (an element, or the D + 2 vertices
// of an interior face's two elements) that all couple with each other.
struct VertexPattern {
  std::vector<int> start, nb;
  int degree(int j) const { return start[j + 1] - start[j]; }
  // position of i among j's neighbours (i must be one)
  int find(int j, int i) const {
    const int* b = nb.data() + start[j];
    return static_cast<int>(std::lower_bound(b, b + degree(j), i) - b);
  }
};

template <class Groups>
VertexPattern vertex_pattern(int n, int count, int size, const Groups& vertex_of) {
  std::vector<std::vector<int>> lists(n);
  for (int g = 0; g < count; ++g)
    for (int a = 0; a < size; ++a) {
      std::vector<int>& L = lists[vertex_of(g, a)];
      for (int b = 0; b < size; ++b) {
        const int v = vertex_of(g, b);
        if (std::find(L.begin(), L.end(), v) == L.end()) L.push_back(v);
      }
    }
  VertexPattern P;
  P.start.assign(n + 1, 0);
  for (int j = 0; j < n; ++j) P.start[j + 1] = P.start[j] + static_cast<int>(lists[j].size());
  P.nb.reserve(P.start[n]);
  for (auto& L : lists) {
    std::sort(L.begin(), L.end());
    P.nb.insert(P.nb.end(), L.begin(), L.end());
  }
  return P;
}

// A sparse matrix (column-major, compressed) on the pattern: rows R i + r (r < R) of every
// neighbour i of vertex j in each of the C columns C j + s, values 0. at(r, j, s, pos) is the
// value of entry (R i + r, C j + s) with pos = P.find(j, i).
struct BlockMatrix {
  int R = 1, C = 1;
  const VertexPattern* P = nullptr;
  SpMat M;
  BlockMatrix(const VertexPattern& pattern, int n, int rows_per_vertex, int cols_per_vertex)
      : R(rows_per_vertex), C(cols_per_vertex), P(&pattern), M(R * n, C * n) {
    M.resizeNonZeros(static_cast<Eigen::Index>(R) * C * pattern.start[n]);
    int* outer = M.outerIndexPtr();
    int* inner = M.innerIndexPtr();
    int k = 0;
    for (int j = 0; j < n; ++j)
      for (int s = 0; s < C; ++s) {
        outer[C * j + s] = k;
        for (int q = pattern.start[j]; q < pattern.start[j + 1]; ++q)
          for (int r = 0; r < R; ++r) inner[k++] = R * pattern.nb[q] + r;
      }
    outer[C * n] = k;
    std::fill(M.valuePtr(), M.valuePtr() + k, 0.0);
  }
  double& at(int r, int j, int s, int pos) {
    return M.valuePtr()[M.outerIndexPtr()[C * j + s] + R * pos + r];
  }
  // the matrix without the entries that stayed exactly 0 (axis-aligned meshes have many)
  SpMat take() {
    M.prune([](const Eigen::Index&, const Eigen::Index&, const double& v) { return v != 0.0; });
    return std::move(M);
  }
};

// Items [0, count) a block of 1024 at a time: compute(i, local) on the library's threads, then
// add(i, local) in item order on the calling thread, so the sums do not depend on the threads.
template <class Local, class Compute, class Add>
void in_blocks(int count, const Compute& compute, const Add& add) {
  constexpr int kBlock = 1024;
  std::vector<Local> buf(static_cast<size_t>(std::min(std::max(count, 1), kBlock)));
  const int threads = thread_count(std::min(count, kBlock), 64);
  for (int i0 = 0; i0 < count; i0 += kBlock) {
    const int i1 = std::min(count, i0 + kBlock);
    parallel_blocks(i1 - i0, 64, threads, [&](long long lo, long long hi) {
      for (int i = i0 + static_cast<int>(lo); i < i0 + hi; ++i) compute(i, buf[static_cast<size_t>(i - i0)]);
    });
    for (int i = i0; i < i1; ++i) add(i, buf[static_cast<size_t>(i - i0)]);
  }
}

// The assembly in dimension D (the same code serves triangles and tetrahedra): the elements'
// basis gradients once, then each energy's pass.
template <int D>
struct FixedAssembly {
  using VecD = Eigen::Matrix<double, D, 1>;
  using Grad = Eigen::Matrix<double, D + 1, D>;  // row k = a_k^T
  static constexpr int NV = D * (D + 1);         // local m unknowns of one element
  static constexpr int NL = D + 2;               // local vertices of a face pair
  static constexpr int NZ = NL * (D + 1);        // local unknowns: m (D each) then x (1 each)
  static constexpr int XOFF = NL * D;
  using FaceVertices = std::array<int, NL>;
  struct FaceLocal {
    Eigen::Matrix<double, NZ, NZ> H;
    int pos[NL][NL];  // pos[p][q]: local vertex p among the neighbours of local vertex q
  };

  const Eigen::MatrixXd& U;
  const Eigen::MatrixXi& T;
  int n, m;
  std::vector<Grad> A;  // basis gradients of every element (the face pass needs both sides')
  std::vector<double> volume;

  FixedAssembly(const Eigen::MatrixXd& U_, const Eigen::MatrixXi& T_)
      : U(U_), T(T_), n(static_cast<int>(U_.rows())), m(static_cast<int>(T_.rows())), A(m), volume(m) {
    parallel_blocks(m, 2048, thread_count(m, 2048), [&](long long e0, long long e1) {
      for (long long e = e0; e < e1; ++e) {
        Eigen::Matrix<double, D, D> E;
        for (int k = 0; k < D; ++k) E.col(k) = u(T(e, k + 1)) - u(T(e, 0));
        const Eigen::Matrix<double, D, D> Einv = E.inverse();
        A[e].template bottomRows<D>() = Einv;
        A[e].row(0) = -Einv.colwise().sum();
        volume[e] = std::abs(E.determinant()) / (D == 2 ? 2.0 : 6.0);
      }
    });
  }
  VecD u(int i) const { return U.row(i).transpose(); }

  // E_vibr: vec(Hess x_c) = L m_local: Hess_pq = sum_k a_k[p] m_k[q] + m_k[p] a_k[q] (fact 2)
  SpMat vibr() const {
    const VertexPattern Pe = vertex_pattern(n, m, D + 1, [&](int e, int a) { return T(e, a); });
    BlockMatrix out(Pe, n, D, D);
    struct Local {
      Eigen::Matrix<double, NV, NV> H;
      int pos[D + 1][D + 1];  // pos[k][l]: T(e, k) among the neighbours of T(e, l)
    };
    const auto compute = [&](int e, Local& Lc) {
      Eigen::Matrix<double, D * D, NV> L = Eigen::Matrix<double, D * D, NV>::Zero();
      for (int k = 0; k <= D; ++k)
        for (int p = 0; p < D; ++p)
          for (int q = 0; q < D; ++q) {
            L(p * D + q, k * D + q) += A[e](k, p);
            L(p * D + q, k * D + p) += A[e](k, q);
          }
      Lc.H.noalias() = volume[e] * (L.transpose() * L);
      for (int k = 0; k <= D; ++k)
        for (int l = 0; l <= D; ++l) Lc.pos[k][l] = Pe.find(T(e, l), T(e, k));
    };
    const auto add = [&](int e, const Local& Lc) {
      for (int l = 0; l <= D; ++l)
        for (int s = 0; s < D; ++s)
          for (int k = 0; k <= D; ++k)
            for (int r = 0; r < D; ++r) out.at(r, T(e, l), s, Lc.pos[k][l]) += Lc.H(k * D + r, l * D + s);
    };
    in_blocks<Local>(m, compute, add);
    return out.take();
  }

  // Local vertices of each face: its D vertices, then the vertex of each side's element off it.
  std::vector<FaceVertices> face_vertices(const Eigen::MatrixXi& F) const {
    std::vector<FaceVertices> local(static_cast<size_t>(F.rows()));
    for (Eigen::Index f = 0; f < F.rows(); ++f) {
      for (int j = 0; j < D; ++j) local[f][j] = F(f, j);
      for (int s = 0; s < 2; ++s) {
        const int e = F(f, D + s);
        for (int k = 0; k <= D; ++k) {
          bool on_face = false;
          for (int j = 0; j < D; ++j) on_face = on_face || T(e, k) == F(f, j);
          if (!on_face) local[f][D + s] = T(e, k);
        }
      }
    }
    return local;
  }

  // E_disc of face f: the jump of grad x_c across it is linear; at a face vertex v the phi_v m_v
  // terms of both sides cancel, leaving sum_k +-a_k (x_k + m_k . (u_v - u_k)) (fact 3).
  void face_hessian(const Eigen::MatrixXi& F, int f, const FaceVertices& lv, Eigen::Matrix<double, NZ, NZ>& H) const {
    auto local_of = [&](int g) {
      for (int j = 0; j < NL; ++j)
        if (lv[j] == g) return j;
      return -1;
    };
    std::array<Eigen::Matrix<double, D, NZ>, D> G;
    for (auto& g : G) g.setZero();
    for (int s = 0; s < 2; ++s) {
      const int e = F(f, D + s);
      const double sgn = s == 0 ? 1.0 : -1.0;
      for (int k = 0; k <= D; ++k) {
        const int j = local_of(T(e, k));
        const VecD a = sgn * A[e].row(k).transpose();
        for (int v = 0; v < D; ++v) {
          const VecD w = u(F(f, v)) - u(T(e, k));
          G[v].col(XOFF + j) += a;
          G[v].template block<D, D>(0, j * D) += a * w.transpose();
        }
      }
    }
    double area;
    if constexpr (D == 2) {
      area = (u(F(f, 1)) - u(F(f, 0))).norm();
    } else {
      area = 0.5 * (u(F(f, 1)) - u(F(f, 0))).cross(u(F(f, 2)) - u(F(f, 0))).norm();
    }
    // integral over a (D-1)-simplex of |g|^2, g linear: |F|/(D(D+1)) (sum |g_v|^2 + |sum g_v|^2)
    Eigen::Matrix<double, D, NZ> Gs = Eigen::Matrix<double, D, NZ>::Zero();
    H.setZero();
    for (int v = 0; v < D; ++v) {
      Gs += G[v];
      H.noalias() += G[v].transpose() * G[v];
    }
    H.noalias() += Gs.transpose() * Gs;
    H *= area / (D * (D + 1));
  }

  // Adds one face's local Hessian into the mm, mx and xx blocks. Local unknown a: m of local
  // vertex a / D, component a % D (a < XOFF); x of local vertex a - XOFF. A column's rows of one
  // neighbour are contiguous in the matrices and in H.
  static void add_face(const FaceLocal& Lc, const FaceVertices& lv, BlockMatrix& dmm, BlockMatrix& dmx,
                       BlockMatrix& dxx) {
    for (int q = 0; q < NL; ++q) {
      for (int s = 0; s < D; ++s) {
        double* col = dmm.M.valuePtr() + dmm.M.outerIndexPtr()[D * lv[q] + s];
        for (int p = 0; p < NL; ++p)
          for (int r = 0; r < D; ++r) col[D * Lc.pos[p][q] + r] += Lc.H(p * D + r, q * D + s);
      }
      double* colx = dmx.M.valuePtr() + dmx.M.outerIndexPtr()[lv[q]];
      for (int p = 0; p < NL; ++p)
        for (int r = 0; r < D; ++r) colx[D * Lc.pos[p][q] + r] += Lc.H(p * D + r, XOFF + q);
      double* colxx = dxx.M.valuePtr() + dxx.M.outerIndexPtr()[lv[q]];
      for (int p = 0; p < NL; ++p) colxx[Lc.pos[p][q]] += Lc.H(XOFF + p, XOFF + q);
    }
  }

  // E_disc's blocks mm, mx, xx into H.
  void disc(Hessians& out) const {
    const Eigen::MatrixXi F = interior_faces(T);
    const int nf = static_cast<int>(F.rows());
    const std::vector<FaceVertices> local = face_vertices(F);
    const VertexPattern Pf = vertex_pattern(n, nf, NL, [&](int f, int a) { return local[f][a]; });
    BlockMatrix dmm(Pf, n, D, D), dmx(Pf, n, D, 1), dxx(Pf, n, 1, 1);
    const auto compute = [&](int f, FaceLocal& Lc) {
      const FaceVertices& lv = local[static_cast<size_t>(f)];
      face_hessian(F, f, lv, Lc.H);
      for (int p = 0; p < NL; ++p)
        for (int q = 0; q < NL; ++q) Lc.pos[p][q] = Pf.find(lv[q], lv[p]);
    };
    const auto add = [&](int f, const FaceLocal& Lc) { add_face(Lc, local[static_cast<size_t>(f)], dmm, dmx, dxx); };
    in_blocks<FaceLocal>(nf, compute, add);
    out.disc_mm = dmm.take();
    out.disc_mx = dmx.take();
    out.disc_xx = dxx.take();
  }
};

template <int D>
Hessians assemble_fixed(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T) {
  const FixedAssembly<D> a(U, T);
  Hessians H;
  H.vibr_mm = a.vibr();
  a.disc(H);
  return H;
}

}  // namespace

Hessians assemble(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T) {
  if (U.cols() == 2) return assemble_fixed<2>(U, T);
  if (U.cols() == 3) return assemble_fixed<3>(U, T);
  throw Error("dimension must be 2 or 3");
}

}  // namespace mbi::interp::detail
