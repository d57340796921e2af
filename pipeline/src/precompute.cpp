// Precompute (see precompute.hpp): the methods' precomputes and the one dispatch on the method.
#include <mbi/base/timer.hpp>
#include <mbi/error.hpp>
#include <mbi/pipeline/precompute.hpp>

#include <cmath>
#include <string>

namespace mbi::pipeline {

Precompute::Precompute(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                       Method method, const interp::Options& options)
    : U_(U), T_(T), options_(options) {
  interp::validate_mesh(U_, T_);
  interp::resolve_alpha(options_, dim());
  interp::check_beta(options_);
  interp::check_max_memory(options_);
  if (needs_solve(method)) solver();
  if (needs_phong(method)) phong();
}

void Precompute::check_pose(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  if (X.rows() != U_.rows() || X.cols() != U_.cols())
    throw Error("X must be " + std::to_string(U_.rows()) + " x " + std::to_string(U_.cols()) + ", got " +
                std::to_string(X.rows()) + " x " + std::to_string(X.cols()));
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    for (Eigen::Index c = 0; c < X.cols(); ++c)
      if (!std::isfinite(X(i, c)))
        throw Error("control vertex " + std::to_string(i) + " has a non-finite coordinate (column " +
                    std::to_string(c) + ")");
}

interp::VertexMatrices Precompute::M(Method method, const Eigen::Ref<const Eigen::MatrixXd>& X) {
  if (needs_solve(method)) solver();
  if (needs_phong(method)) phong();
  return std::as_const(*this).M(method, X);
}

interp::VertexMatrices Precompute::M(Method method, const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  check_pose(X);
  switch (method) {
    case Method::ModifiedBI:
      if (!solver_) throw Error("modified-BI's precompute was not built");
      return solver_->solve(X);
    case Method::Phong:
      if (!phong_) throw Error("Phong's vertex weights were not built");
      return phong_->M(X);
    case Method::BI: break;
  }
  return interp::VertexMatrices::Zero(U_.rows() * U_.cols(), U_.cols());
}

interp::BezierPoints Precompute::bezier(Method method, const Eigen::Ref<const Eigen::MatrixXd>& X,
                                        const interp::VertexMatrices& M) const {
  if (method == Method::BI) return interp::bezier_bi(X, T_);
  return interp::bezier_points(U_, T_, X, M);
}

interp::BezierPoints Precompute::bezier(Method method, const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  if (method != Method::BI) return bezier(method, X, M(method, X));
  check_pose(X);
  return interp::bezier_bi(X, T_);
}

const interp::BezierPoints& Precompute::bezier(Method method, const Eigen::Ref<const Eigen::MatrixXd>& X,
                                               PoseScratch& scratch) const {
  const int d = dim();
  scratch.B.resize(T_.rows() * ((d + 1) * (d + 2) / 2), d);
  if (method == Method::BI) {
    check_pose(X);
    interp::bezier_bi(X, T_, scratch.B);
    return scratch.B;
  }
  scratch.M.resize(U_.rows() * d, d);
  M(method, X, scratch.M);
  interp::bezier_points(U_, T_, X, scratch.M, scratch.B);
  return scratch.B;
}

void Precompute::M(Method method, const Eigen::Ref<const Eigen::MatrixXd>& X,
                   interp::MatrixOut out) const {
  check_pose(X);
  switch (method) {
    case Method::ModifiedBI:
      if (!solver_) throw Error("modified-BI's precompute was not built");
      return solver_->solve(X, out);
    case Method::Phong:
      if (!phong_) throw Error("Phong's vertex weights were not built");
      return phong_->M(X, out);
    case Method::BI: break;
  }
  if (out.rows() != U_.rows() * U_.cols() || out.cols() != U_.cols())
    throw Error("M must be " + std::to_string(U_.rows() * U_.cols()) + " x " + std::to_string(U_.cols()));
  out.setZero();
}

Eigen::MatrixXd Precompute::M_transpose(Method method, const interp::VertexMatrices& G) const {
  Eigen::MatrixXd out(U_.rows(), U_.cols());
  M_transpose(method, G, out);
  return out;
}

void Precompute::M_transpose(Method method, const Eigen::Ref<const interp::VertexMatrices>& G,
                             Eigen::Ref<Eigen::MatrixXd> out) const {
  switch (method) {
    case Method::ModifiedBI:
      if (!solver_) throw Error("modified-BI's precompute was not built");
      return solver_->solve_transpose(G, out);
    case Method::Phong:
      if (!phong_) throw Error("Phong's vertex weights were not built");
      return phong_->M_transpose(G, out);
    case Method::BI: break;
  }
  if (out.rows() != U_.rows() || out.cols() != U_.cols())
    throw Error("dL/dX must be " + std::to_string(U_.rows()) + " x " + std::to_string(U_.cols()));
  out.setZero();
}

const interp::ModifiedBI& Precompute::solver() {
  if (!solver_) {
    const auto t0 = Clock::now();
    solver_.emplace(U_, T_, options_);
    precompute_ms_ = ms_since(t0);
  }
  return *solver_;
}

const interp::Phong& Precompute::phong() {
  if (!phong_) {
    const auto t0 = Clock::now();
    phong_.emplace(U_, T_);
    phong_ms_ = ms_since(t0);
  }
  return *phong_;
}

void Precompute::set_alpha(double alpha) {
  interp::check_alpha(alpha);
  if (solver_) {
    const auto t0 = Clock::now();
    solver_->set_alpha(alpha);
    precompute_ms_ = ms_since(t0);
  }
  options_.alpha = alpha;
}

}  // namespace mbi::pipeline
