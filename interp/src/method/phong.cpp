// Phong deformation's closed-form M (phong.hpp).
#include <mbi/interp/phong.hpp>

#include "method/detail.hpp"

#include <cmath>
#include <string>

namespace mbi::interp {

Phong::Phong(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T)
    : U_(U), T_(T) {
  validate_mesh(U, T);
  const int n = static_cast<int>(U.rows()), d = static_cast<int>(U.cols());
  const int m = static_cast<int>(T.rows());
  Dm_inv_.resize(static_cast<Eigen::Index>(m) * d, d);
  Eigen::MatrixXd centroids(m, d);
  elements_of_.assign(static_cast<size_t>(n), {});
  for (int e = 0; e < m; ++e) {
    Eigen::MatrixXd Dm(d, d);
    for (int k = 0; k < d; ++k) Dm.col(k) = (U.row(T(e, k + 1)) - U.row(T(e, 0))).transpose();
    Dm_inv_.middleRows(static_cast<Eigen::Index>(e) * d, d) = Dm.inverse();
    centroids.row(e) = Eigen::RowVectorXd::Zero(d);
    for (int k = 0; k <= d; ++k) {
      centroids.row(e) += U.row(T(e, k)) / (d + 1);
      elements_of_[static_cast<size_t>(T(e, k))].push_back(e);
    }
  }
  weights_.assign(static_cast<size_t>(n), {});
  lambda_ = Eigen::MatrixXd::Zero(n, d);
  for (int i = 0; i < n; ++i) {
    const std::vector<int>& es = elements_of_[static_cast<size_t>(i)];
    if (es.empty()) continue;
    const size_t k = es.size();
    std::vector<Eigen::VectorXd> rh(k);
    std::vector<double> len(k);
    Eigen::MatrixXd S = Eigen::MatrixXd::Identity(d, d);
    Eigen::VectorXd s = Eigen::VectorXd::Zero(d);
    for (size_t a = 0; a < k; ++a) {
      const Eigen::VectorXd r = (centroids.row(es[a]) - U.row(i)).transpose();
      len[a] = r.norm();  // > 0: the centroid of a valid element is not one of its vertices
      rh[a] = r / len[a];
      S += rh[a] * rh[a].transpose();
      s += rh[a];
    }
    const Eigen::VectorXd lambda = -S.ldlt().solve(s);  // I + sum rh rh^T is SPD
    lambda_.row(i) = lambda.transpose();
    std::vector<double>& w = weights_[static_cast<size_t>(i)];
    w.resize(k);
    double sum = 0, abs_sum = 0;
    for (size_t a = 0; a < k; ++a) {
      w[a] = (1 + lambda.dot(rh[a])) / len[a];
      sum += w[a];
      abs_sum += std::abs(w[a]);
    }
    if (!(sum > 1e-3 * abs_sum)) {
      // the correction (nearly) cancelled the weights: plain Shepard weights for this vertex
      ++fallback_;
      sum = 0;
      for (size_t a = 0; a < k; ++a) sum += (w[a] = 1 / len[a]);
    }
    for (double& x : w) x /= sum;
  }
}

namespace {
void check_size(const char* what, const MatrixIn& A, Eigen::Index rows, Eigen::Index cols) {
  if (A.rows() != rows || A.cols() != cols)
    throw Error(std::string(what) + " must be " + std::to_string(rows) + " x " + std::to_string(cols) + ", got " +
                std::to_string(A.rows()) + " x " + std::to_string(A.cols()));
}
}  // namespace

Eigen::MatrixXd Phong::element_gradients(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  Eigen::MatrixXd F;
  element_gradients(X, F);
  return F;
}

// F is resized to (m d) x d (no allocation when it has that size already).
void Phong::element_gradients(const Eigen::Ref<const Eigen::MatrixXd>& X, Eigen::MatrixXd& F) const {
  const int d = dim(), m = elements();
  check_size("X", X, U_.rows(), d);
  detail::check_finite("deformed vertex", X);
  F.resize(static_cast<Eigen::Index>(m) * d, d);
  Eigen::MatrixXd Ds(d, d);
  for (int e = 0; e < m; ++e) {
    for (int k = 0; k < d; ++k) Ds.col(k) = (X.row(T_(e, k + 1)) - X.row(T_(e, 0))).transpose();
    F.middleRows(static_cast<Eigen::Index>(e) * d, d).noalias() =
        Ds * Dm_inv_.middleRows(static_cast<Eigen::Index>(e) * d, d);
  }
}

Eigen::MatrixXd Phong::vertex_gradients(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  Eigen::MatrixXd Fe;
  element_gradients(X, Fe);
  Eigen::MatrixXd F(static_cast<Eigen::Index>(vertices()) * dim(), dim());
  vertex_gradients(Fe, F);
  return F;
}

void Phong::vertex_gradients(const Eigen::MatrixXd& Fe, MatrixOut F) const {
  const int d = dim(), n = vertices();
  F.setZero();
  for (int i = 0; i < n; ++i) {
    const std::vector<int>& es = elements_of_[static_cast<size_t>(i)];
    const std::vector<double>& w = weights_[static_cast<size_t>(i)];
    for (size_t a = 0; a < es.size(); ++a)
      F.middleRows(static_cast<Eigen::Index>(i) * d, d) +=
          w[a] * Fe.middleRows(static_cast<Eigen::Index>(es[a]) * d, d);
  }
}

VertexMatrices Phong::M(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  VertexMatrices out(static_cast<Eigen::Index>(vertices()) * dim(), dim());
  M(X, out);
  return out;
}

void Phong::M(const Eigen::Ref<const Eigen::MatrixXd>& X, MatrixOut out) const {
  check_size("M", out, static_cast<Eigen::Index>(vertices()) * dim(), dim());
  thread_local Eigen::MatrixXd Fe;  // the element gradients, kept per thread (no allocation per frame)
  element_gradients(X, Fe);
  vertex_gradients(Fe, out);
  out *= 0.5;
}

Eigen::MatrixXd Phong::M_transpose(const VertexMatrices& G) const {
  Eigen::MatrixXd GX(vertices(), dim());
  M_transpose(G, GX);
  return GX;
}

void Phong::M_transpose(const Eigen::Ref<const VertexMatrices>& G, Eigen::Ref<Eigen::MatrixXd> GX) const {
  const int d = dim(), n = vertices(), m = elements();
  check_size("dL/dM", G, static_cast<Eigen::Index>(n) * d, d);
  check_size("dL/dX", GX, n, d);
  detail::check_finite("dL/dM row", G);
  // M_i = sum_e w_e F_e / 2: dL/dF_e gathers w_e dL/dM_i / 2 from every vertex i of e
  thread_local Eigen::MatrixXd GF;  // kept per thread
  GF.setZero(static_cast<Eigen::Index>(m) * d, d);
  for (int i = 0; i < n; ++i) {
    const std::vector<int>& es = elements_of_[static_cast<size_t>(i)];
    const std::vector<double>& w = weights_[static_cast<size_t>(i)];
    for (size_t a = 0; a < es.size(); ++a)
      GF.middleRows(static_cast<Eigen::Index>(es[a]) * d, d) +=
          0.5 * w[a] * G.middleRows(static_cast<Eigen::Index>(i) * d, d);
  }
  // F_e = D_s D_m^-1 with D_s's column k = x_{k+1} - x_0: dL/dD_s = dL/dF_e D_m^-T
  GX.setZero();
  Eigen::MatrixXd GDs(d, d);
  for (int e = 0; e < m; ++e) {
    GDs.noalias() = GF.middleRows(static_cast<Eigen::Index>(e) * d, d) *
                    Dm_inv_.middleRows(static_cast<Eigen::Index>(e) * d, d).transpose();
    for (int k = 0; k < d; ++k) {
      GX.row(T_(e, k + 1)) += GDs.col(k).transpose();
      GX.row(T_(e, 0)) -= GDs.col(k).transpose();
    }
  }
}

}  // namespace mbi::interp
