// Quality metrics: per-face discontinuity energy, E_vibr, Table 2 (fact 12).
#include <mbi/interp/metrics.hpp>

#include <mbi/interp/evaluate.hpp>

#include "method/detail.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace mbi::interp {
namespace {
double ratio_of(double a, double b) {
  return b > 0 ? a / b : (a > 0 ? std::numeric_limits<double>::infinity() : 1.0);
}

void check_xm(const Eigen::Ref<const Eigen::MatrixXd>& U,
              const Eigen::Ref<const Eigen::MatrixXd>* X, const VertexMatrices& M) {
  const auto n = U.rows(), d = U.cols();
  if (X && (X->rows() != n || X->cols() != d))
    throw Error("X must be " + std::to_string(n) + " x " + std::to_string(d) +
                ", got " + std::to_string(X->rows()) + " x " + std::to_string(X->cols()));
  if (M.rows() != n * d || M.cols() != d)
    throw Error("M must be " + std::to_string(n * d) + " x " + std::to_string(d) +
                ", got " + std::to_string(M.rows()) + " x " + std::to_string(M.cols()));
}
std::string magnitude(const Eigen::Ref<const Eigen::MatrixXd>& A) {
  char b[40];
  std::snprintf(b, sizeof b, "%.3g", A.size() ? A.cwiseAbs().maxCoeff() : 0.0);
  return b;
}

// Every energy and summary finite, or OverflowError naming the cause.
void check_finite_table(const DiscontinuityTable& t, const Eigen::Ref<const Eigen::MatrixXd>& X,
                        const VertexMatrices& M) {
  bool ok = std::isfinite(t.e_vibr) && std::isfinite(t.e_disc) && std::isfinite(t.e_total);
  for (const Summary* s : {&t.bi, &t.modified_bi})
    ok = ok && std::isfinite(s->mean) && std::isfinite(s->std) && std::isfinite(s->max);
  if (t.phong) ok = ok && std::isfinite(t.phong->mean) && std::isfinite(t.phong->std) &&
                    std::isfinite(t.phong->max);
  if (!ok)
    throw OverflowError("the energies overflow a double (control positions up "
                        "to " + magnitude(X) + ", matrices M up to " + magnitude(M) +
                        "; the energies grow with their square)");
}
}  // namespace

Eigen::VectorXd face_discontinuity(const Eigen::Ref<const Eigen::MatrixXd>& U,
                                   const Eigen::Ref<const Eigen::MatrixXi>& T,
                                   const Eigen::Ref<const Eigen::MatrixXd>& X,
                                   const VertexMatrices& M) {
  detail::check_shapes(U, T);
  check_xm(U, &X, M);
  const int d = static_cast<int>(U.cols());
  const Eigen::MatrixXi F = interior_faces(T);
  Eigen::VectorXd E(F.rows());
  for (int f = 0; f < F.rows(); ++f) {
    // jump of the full gradient (d x d, row c = grad x_c) at each face vertex; the phi_v M_v
    // terms of both sides cancel there (fact 3)
    std::vector<Eigen::MatrixXd> g(d, Eigen::MatrixXd::Zero(d, d));
    for (int s = 0; s < 2; ++s) {
      const int e = F(f, d + s);
      const double sgn = s == 0 ? 1.0 : -1.0;
      const Eigen::MatrixXd A = basis_gradients(U, T, e);
      for (int k = 0; k <= d; ++k) {
        const int i = T(e, k);
        for (int v = 0; v < d; ++v) {
          const Eigen::VectorXd w = (U.row(F(f, v)) - U.row(i)).transpose();
          const Eigen::VectorXd val = X.row(i).transpose() + M.middleRows(i * d, d) * w;  // per c
          g[v] += sgn * (val * A.row(k));
        }
      }
    }
    double area;
    if (d == 2) {
      area = (U.row(F(f, 1)) - U.row(F(f, 0))).norm();
    } else {
      const Eigen::Vector3d e1 = (U.row(F(f, 1)) - U.row(F(f, 0))).transpose();
      const Eigen::Vector3d e2 = (U.row(F(f, 2)) - U.row(F(f, 0))).transpose();
      area = 0.5 * e1.cross(e2).norm();
    }
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(d, d);
    double sq = 0;
    for (int v = 0; v < d; ++v) {
      sum += g[v];
      sq += g[v].squaredNorm();
    }
    E(f) = area / (d * (d + 1)) * (sq + sum.squaredNorm());
  }
  return E;
}

Summary summarize(const Eigen::Ref<const Eigen::VectorXd>& values) {
  Summary s;
  if (values.size() == 0) return s;
  // overflow-safe for finite values: the mean of v/n, the deviation scaled by its largest term
  const double n = static_cast<double>(values.size());
  s.mean = (values.array() / n).sum();
  s.max = values.maxCoeff();
  const double big = (values.array() - s.mean).abs().maxCoeff();
  s.std = big > 0 ? big * std::sqrt((((values.array() - s.mean) / big).square() / n).sum()) : 0.0;
  if (!std::isfinite(big)) s.std = big;
  return s;
}

DiscontinuityTable discontinuity_table(const ModifiedBI& solver,
                                       const Eigen::Ref<const Eigen::MatrixXd>& X,
                                       const VertexMatrices& M) {
  const Eigen::MatrixXd& U = solver.rest_positions();
  const Eigen::MatrixXi& T = solver.elements_matrix();
  DiscontinuityTable t;
  const VertexMatrices Z = VertexMatrices::Zero(M.rows(), M.cols());
  const Eigen::VectorXd bi = face_discontinuity(U, T, X, Z);
  const Eigen::VectorXd mb = face_discontinuity(U, T, X, M);
  t.faces = static_cast<int>(bi.size());
  t.bi = summarize(bi);
  t.modified_bi = summarize(mb);
  t.ratio.mean = ratio_of(t.bi.mean, t.modified_bi.mean);
  t.ratio.std = ratio_of(t.bi.std, t.modified_bi.std);
  t.ratio.max = ratio_of(t.bi.max, t.modified_bi.max);
  t.e_vibr = vibration_energy(U, T, M);
  t.e_disc = mb.sum();
  t.e_total = solver.alpha() * t.e_vibr + solver.beta() * t.e_disc;
  check_finite_table(t, X, M);
  return t;
}

DiscontinuityTable discontinuity_table(const ModifiedBI& solver,
                                       const Eigen::Ref<const Eigen::MatrixXd>& X,
                                       const VertexMatrices& M, const VertexMatrices& M_phong) {
  DiscontinuityTable t = discontinuity_table(solver, X, M);
  const Summary ph =
      summarize(face_discontinuity(solver.rest_positions(), solver.elements_matrix(), X, M_phong));
  t.phong = ph;
  t.phong_ratio.mean = ratio_of(t.bi.mean, ph.mean);
  t.phong_ratio.std = ratio_of(t.bi.std, ph.std);
  t.phong_ratio.max = ratio_of(t.bi.max, ph.max);
  check_finite_table(t, X, M_phong);
  return t;
}

Accuracy accuracy(const BezierPoints& B, const Embedding& emb,
                  const Eigen::Ref<const Eigen::MatrixXd>& rest,
                  const Eigen::Ref<const Eigen::MatrixXd>& exact,
                  const Eigen::Ref<const Eigen::MatrixXd>& exact_gradients) {
  const int d = emb.dim(), p = emb.size();
  const int K = (d + 1) * (d + 2) / 2;
  const Eigen::Index m = emb.gradients.rows() / (d + 1);
  if (emb.gradients.rows() != m * (d + 1) || emb.gradients.cols() != d || m == 0)
    throw Error("the embedding has no basis gradients (use embed())");
  if (B.rows() != m * K || B.cols() != d)
    throw Error("Bezier points must be " + std::to_string(m * K) + " x " + std::to_string(d));
  if (rest.rows() != p || rest.cols() != d || exact.rows() != p || exact.cols() != d)
    throw Error("rest and exact must be " + std::to_string(p) + " x " + std::to_string(d));
  if (exact_gradients.rows() != static_cast<Eigen::Index>(p) * d || exact_gradients.cols() != d)
    throw Error("exact_gradients must be " + std::to_string(p * d) + " x " + std::to_string(d));
  Accuracy a;
  if (p == 0) return a;
  a.size = (rest.colwise().maxCoeff() - rest.colwise().minCoeff()).norm();
  Eigen::MatrixXd x;
  evaluate<double>(B, emb, x);
  const auto& edges = bezier_edges(d);
  double pos2 = 0, pos_max = 0, jac2 = 0, ref2 = 0, jac_max = 0;
  Eigen::MatrixXd g(d, d + 1);
  for (int q = 0; q < p; ++q) {
    const double dx = (x.row(q) - exact.row(q)).norm();
    pos2 += dx * dx;
    pos_max = std::max(pos_max, dx);
    // J = sum_k g_k a_k^T with g_k = 2 phi_k x_k + sum_{edges (k, j)} 2 phi_j P_kj (fact 6)
    const Eigen::Index e = emb.element(q);
    for (int k = 0; k <= d; ++k) g.col(k) = 2 * emb.bary(q, k) * B.row(e * K + k).transpose();
    for (size_t s = 0; s < edges.size(); ++s) {
      const auto [i, j] = edges[s];
      const Eigen::Index row = e * K + d + 1 + static_cast<Eigen::Index>(s);
      g.col(i) += 2 * emb.bary(q, j) * B.row(row).transpose();
      g.col(j) += 2 * emb.bary(q, i) * B.row(row).transpose();
    }
    const Eigen::MatrixXd J = g * emb.gradients.middleRows(e * (d + 1), d + 1);
    const Eigen::MatrixXd Dg = exact_gradients.middleRows(static_cast<Eigen::Index>(q) * d, d);
    const double dj = (J - Dg).squaredNorm(), r = Dg.squaredNorm();
    jac2 += dj;
    ref2 += r;
    jac_max = std::max(jac_max, r > 0 ? std::sqrt(dj / r) : (dj > 0 ? std::numeric_limits<double>::infinity() : 0.0));
  }
  const double size = a.size > 0 ? a.size : 1.0;
  a.position_rms = std::sqrt(pos2 / p) / size;
  a.position_max = pos_max / size;
  a.gradient_rms = ref2 > 0 ? std::sqrt(jac2 / ref2) : std::sqrt(jac2);
  a.gradient_max = jac_max;
  return a;
}

double vibration_energy(const Eigen::Ref<const Eigen::MatrixXd>& U,
                        const Eigen::Ref<const Eigen::MatrixXi>& T, const VertexMatrices& M) {
  detail::check_shapes(U, T);
  check_xm(U, nullptr, M);
  const int d = static_cast<int>(U.cols());
  double E = 0;
  for (int e = 0; e < T.rows(); ++e) {
    const Eigen::MatrixXd A = basis_gradients(U, T, e);
    const double vol = std::abs(element_volume(U, T, e));
    for (int c = 0; c < d; ++c) {
      Eigen::MatrixXd S = Eigen::MatrixXd::Zero(d, d);  // sum_k a_k m_k^T
      for (int k = 0; k <= d; ++k) S += A.row(k).transpose() * M.row(T(e, k) * d + c);
      const Eigen::MatrixXd H = S + S.transpose();
      E += vol * H.squaredNorm();
    }
  }
  return E;
}

}  // namespace mbi::interp
