// Interactive control (paper Eq. 10 / 11, method.md fact 10).
#include <mbi/interp/control.hpp>

#include "method/detail.hpp"

#include <Eigen/SparseCholesky>
#include <cmath>

namespace mbi::interp {

using SpMat = Eigen::SparseMatrix<double>;

struct HandleSolver::Impl {
  int d = 3, n = 0;
  Eigen::MatrixXd U;
  Eigen::MatrixXi T;
  std::vector<int> handles;
  ControlOptions opt;
  double alpha = 0, beta = 0, gamma = 0, lambda = 0;
  SpMat R;        // selection of the unknowns y from the full per-component vector [m; x]
  SpMat Hyh;      // coupling of y to the handle positions (Hard)
  Eigen::VectorXd reg_mask;  // (n) 1 where the pull toward the previous pose acts
  std::vector<int> m_index, x_index;  // full m / x index -> y index or -1
  Eigen::SimplicialLLT<SpMat> llt;
  VertexMatrices M;
};

HandleSolver::HandleSolver(const Eigen::Ref<const Eigen::MatrixXd>& U,
                           const Eigen::Ref<const Eigen::MatrixXi>& T, std::vector<int> handles,
                           const ControlOptions& options)
    : impl_(std::make_unique<Impl>()) {
  validate_mesh(U, T);
  Impl& I = *impl_;
  I.U = U;
  I.T = T;
  I.d = static_cast<int>(U.cols());
  I.n = static_cast<int>(U.rows());
  I.opt = options;
  const int d = I.d, n = I.n;
  if (handles.empty()) throw Error("the handle set is empty");
  std::vector<char> is_handle(n, 0);
  for (size_t h = 0; h < handles.size(); ++h) {
    const int v = handles[h];
    if (v < 0 || v >= n)
      throw Error("handle " + std::to_string(h) + " is vertex " + std::to_string(v) +
                  ", outside [0, " + std::to_string(n) + ")");
    if (is_handle[v]) throw Error("vertex " + std::to_string(v) + " is a handle twice");
    is_handle[v] = 1;
  }
  I.handles = std::move(handles);
  const Options& io = options.interp;
  I.alpha = resolve_alpha(io, d);
  check_beta(io);
  if (!(options.gamma >= 0) || !std::isfinite(options.gamma))
    throw Error("gamma must be >= 0 (0 selects the automatic rule), got " + std::to_string(options.gamma));
  if (!(options.regularization >= 0) || !std::isfinite(options.regularization))
    throw Error("regularization must be >= 0, got " + std::to_string(options.regularization));

  const detail::Hessians Hs = detail::assemble(I.U, I.T);
  if (Hs.disc_mm.nonZeros() == 0)
    throw Error("the control mesh has no interior faces (a single element?)");
  I.beta = io.beta > 0 ? io.beta : Hs.vibr_mm.norm() / Hs.disc_mm.norm();

  // Full per-component Hessian of E_total over z = [m (d n); x (n)].
  const int nz = d * n + n;
  std::vector<Eigen::Triplet<double>> tz;
  auto add = [&](const SpMat& S, double w, int r0, int c0, bool both) {
    for (int k = 0; k < S.outerSize(); ++k)
      for (SpMat::InnerIterator it(S, k); it; ++it) {
        tz.emplace_back(r0 + static_cast<int>(it.row()), c0 + static_cast<int>(it.col()), w * it.value());
        if (both) tz.emplace_back(c0 + static_cast<int>(it.col()), r0 + static_cast<int>(it.row()), w * it.value());
      }
  };
  add(Hs.vibr_mm, I.alpha, 0, 0, false);
  add(Hs.disc_mm, I.beta, 0, 0, false);
  add(Hs.disc_mx, I.beta, 0, d * n, true);
  add(Hs.disc_xx, I.beta, d * n, d * n, false);

  const bool hard = options.mode == HandleMode::Hard;
  // Frobenius norm of the position block of E_total over the position unknowns.
  double pos_norm2 = 0;
  for (int k = 0; k < Hs.disc_xx.outerSize(); ++k)
    for (SpMat::InnerIterator it(Hs.disc_xx, k); it; ++it)
      if (!hard || (!is_handle[it.row()] && !is_handle[it.col()])) pos_norm2 += std::pow(I.beta * it.value(), 2);
  const double pos_norm = std::sqrt(pos_norm2);
  const int h = static_cast<int>(I.handles.size());
  const int n_pos = hard ? n - h : n;
  if (!hard) {
    // Eq. 11: ||gamma E_pos''||_F = ||E_total''||_F over positions (E_pos'' = identity on handles)
    I.gamma = options.gamma > 0 ? options.gamma : pos_norm / std::sqrt(static_cast<double>(h));
    for (int v : I.handles) tz.emplace_back(d * n + v, d * n + v, I.gamma);
  }
  // Handles that do not span an affine frame leave affine motions free: add the weak pull.
  Eigen::MatrixXd Ah(h, d + 1);
  for (int k = 0; k < h; ++k) {
    Ah.row(k).head(d) = I.U.row(I.handles[k]);
    Ah(k, d) = 1.0;
  }
  Eigen::FullPivLU<Eigen::MatrixXd> lu(Ah);
  lu.setThreshold(1e-9);
  I.reg_mask = Eigen::VectorXd::Zero(n);
  if (lu.rank() < d + 1 && n_pos > 0) {
    if (options.regularization <= 0)
      throw Error("fewer than d+1 affinely independent handles need regularization > 0");
    I.lambda = options.regularization * pos_norm / std::sqrt(static_cast<double>(n_pos));
    for (int v = 0; v < n; ++v)
      if (!hard || !is_handle[v]) {
        I.reg_mask(v) = 1.0;
        tz.emplace_back(d * n + v, d * n + v, I.lambda);
      }
  }
  SpMat Hz(nz, nz);
  Hz.setFromTriplets(tz.begin(), tz.end());

  // Unknowns: m minus boundary (optional) and gauge pins; x minus handles (Hard).
  std::vector<char> free_vertex(n, 0);
  for (int e = 0; e < T.rows(); ++e)
    for (int j = 0; j <= d; ++j) free_vertex[T(e, j)] = 1;
  std::vector<char> used = free_vertex;
  if (io.pin_boundary) {
    const Eigen::VectorXi b = boundary_vertices(n, T);
    for (int i = 0; i < n; ++i)
      if (b(i)) free_vertex[i] = 0;
  }
  int null_dim = 0;
  const std::vector<char> pinned = detail::gauge_pins(I.U, I.T, free_vertex, null_dim);
  I.m_index.assign(static_cast<size_t>(d) * n, -1);
  I.x_index.assign(n, -1);
  int ny = 0;
  for (int a = 0; a < d * n; ++a)
    if (free_vertex[a / d] && !pinned[a]) I.m_index[a] = ny++;
  for (int v = 0; v < n; ++v) {
    if (!used[v])
      throw Error("vertex " + std::to_string(v) + " belongs to no element");
    if (!(hard && is_handle[v])) I.x_index[v] = ny++;
  }
  std::vector<Eigen::Triplet<double>> tr, th;
  for (int a = 0; a < d * n; ++a)
    if (I.m_index[a] >= 0) tr.emplace_back(I.m_index[a], a, 1.0);
  for (int v = 0; v < n; ++v)
    if (I.x_index[v] >= 0) tr.emplace_back(I.x_index[v], d * n + v, 1.0);
  I.R.resize(ny, nz);
  I.R.setFromTriplets(tr.begin(), tr.end());
  const SpMat Rt = I.R.transpose();
  const SpMat Hyy = I.R * Hz * Rt;
  if (hard) {
    for (int k = 0; k < h; ++k) th.emplace_back(d * n + I.handles[k], k, 1.0);
    SpMat C(nz, h);
    C.setFromTriplets(th.begin(), th.end());
    I.Hyh = I.R * Hz * C;
  }
  I.llt.compute(Hyy);
  if (I.llt.info() != Eigen::Success)
    throw Error("Cholesky factorisation failed: the handle problem is not positive definite");
  I.M = VertexMatrices::Zero(static_cast<Eigen::Index>(d) * n, d);
}

HandleSolver::~HandleSolver() = default;
HandleSolver::HandleSolver(HandleSolver&&) noexcept = default;
HandleSolver& HandleSolver::operator=(HandleSolver&&) noexcept = default;

Eigen::MatrixXd HandleSolver::solve(const Eigen::Ref<const Eigen::MatrixXd>& targets,
                                    const Eigen::MatrixXd& previous) {
  Impl& I = *impl_;
  const int d = I.d, n = I.n, h = static_cast<int>(I.handles.size());
  if (targets.rows() != h || targets.cols() != d)
    throw Error("targets must be " + std::to_string(h) + " x " + std::to_string(d) +
                ", got " + std::to_string(targets.rows()) + " x " + std::to_string(targets.cols()));
  detail::check_finite("target", targets);
  const Eigen::MatrixXd& prev = previous.size() == 0 ? I.U : previous;
  if (prev.rows() != n || prev.cols() != d)
    throw Error("previous pose must be " + std::to_string(n) + " x " +
                std::to_string(d) + " or empty, got " + std::to_string(prev.rows()) + " x " +
                std::to_string(prev.cols()));
  detail::check_finite("previous vertex", prev);
  const bool hard = I.opt.mode == HandleMode::Hard;
  // right-hand side on the full vector z = [m; x], then restricted
  Eigen::MatrixXd bz = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(d) * n + n, d);
  bz.bottomRows(n) = I.lambda * (I.reg_mask.asDiagonal() * prev);
  if (!hard)
    for (int k = 0; k < h; ++k) bz.row(d * n + I.handles[k]) += I.gamma * targets.row(k);
  Eigen::MatrixXd rhs = I.R * bz;
  if (hard) rhs -= I.Hyh * targets;
  const Eigen::MatrixXd Y = I.llt.solve(rhs);
  Eigen::MatrixXd X(n, d);
  for (int v = 0; v < n; ++v)
    if (I.x_index[v] >= 0) X.row(v) = Y.row(I.x_index[v]);
  if (hard)
    for (int k = 0; k < h; ++k) X.row(I.handles[k]) = targets.row(k);
  I.M.setZero();
  for (int a = 0; a < d * n; ++a) {
    if (I.m_index[a] < 0) continue;
    const int i = a / d, r = a % d;
    for (int c = 0; c < d; ++c) I.M(i * d + c, r) = Y(I.m_index[a], c);
  }
  return X;
}

const VertexMatrices& HandleSolver::last_M() const { return impl_->M; }
double HandleSolver::gamma() const { return impl_->gamma; }
const std::vector<int>& HandleSolver::handles() const { return impl_->handles; }

}  // namespace mbi::interp
