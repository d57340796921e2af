#pragma once
// The methods over one rest control mesh: their precomputes and the one dispatch on the method.
// Deformer (bind once, deform many) and FramePipeline (drive, solve, evaluate every frame) are
// both built on it, so M and the element Bezier points of a pose are computed in one place.
//
//   Precompute pre(U, T, Method::ModifiedBI, {.alpha = 0.1});   // factorises now
//   interp::VertexMatrices M = pre.M(Method::ModifiedBI, X);
//   interp::BezierPoints B = pre.bezier(Method::ModifiedBI, X, M);
//
// Shapes as in mbi::interp: U, X n x d (d = 2 or 3), T m x (d+1), M (n d) x d, Bezier points
// (m K) x d. The precompute of the method named at construction runs then; another method's
// (modified-BI's factorisation, Phong's vertex weights) runs when first asked for, so a BI
// pipeline pays for modified-BI only when a comparison needs it.
//
// Errors: mbi::Error on an invalid mesh or option (interp's checks), a pose of the wrong shape
// or with a non-finite coordinate. Not for several threads at once when a method is built on
// demand; the const calls on the constructed method may run concurrently.
#include <mbi/interp/modified_bi.hpp>
#include <mbi/interp/phong.hpp>
#include <mbi/pipeline/method.hpp>

#include <optional>

namespace mbi::pipeline {

class Precompute {
 public:
  /// Validates the rest mesh (interp::validate_mesh) and runs `method`'s precompute.
  Precompute(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
             Method method, const interp::Options& options = {});

  int dim() const { return static_cast<int>(U_.cols()); }
  const Eigen::MatrixXd& rest_positions() const { return U_; }
  const Eigen::MatrixXi& elements() const { return T_; }
  const interp::Options& options() const { return options_; }

  /// Throws Error unless X is n x d with finite coordinates (BI and the float kernel would carry
  /// a NaN into every point).
  void check_pose(const Eigen::Ref<const Eigen::MatrixXd>& X) const;

  /// The method's M at pose X ((n d) x d; zero for BI). Builds the method's precompute if needed.
  interp::VertexMatrices M(Method method, const Eigen::Ref<const Eigen::MatrixXd>& X);
  /// The same for a method already built (the one named at construction): no state changes.
  interp::VertexMatrices M(Method method, const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  /// The element Bezier points at pose X from the method's M (BI ignores M).
  interp::BezierPoints bezier(Method method, const Eigen::Ref<const Eigen::MatrixXd>& X,
                              const interp::VertexMatrices& M) const;
  /// M and the Bezier points at X in one call, for a method already built (BI forms no M).
  interp::BezierPoints bezier(Method method, const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  /// A pose's M and Bezier points, sized on their first use and reused by the next poses.
  struct PoseScratch {
    interp::VertexMatrices M;
    interp::BezierPoints B;
  };
  /// The same into scratch (its B, returned); after the first pose nothing is allocated.
  const interp::BezierPoints& bezier(Method method, const Eigen::Ref<const Eigen::MatrixXd>& X,
                                     PoseScratch& scratch) const;
  /// M into caller memory ((n d) x d already), for a method already built; zero for BI.
  void M(Method method, const Eigen::Ref<const Eigen::MatrixXd>& X, interp::MatrixOut out) const;
  /// The transpose of M(method, X), which is linear in X: dL/dX (n x d) from G = dL/dM ((n d) x d),
  /// for a method already built; zero for BI.
  Eigen::MatrixXd M_transpose(Method method, const interp::VertexMatrices& G) const;
  /// The same into caller memory (n x d already).
  void M_transpose(Method method, const Eigen::Ref<const interp::VertexMatrices>& G,
                   Eigen::Ref<Eigen::MatrixXd> out) const;

  /// Modified-BI's factorisation, built on first use (timed: precompute_ms()).
  const interp::ModifiedBI& solver();
  /// Phong's vertex weights, built on first use (timed: phong_ms()).
  const interp::Phong& phong();
  /// The built parts, or nullptr.
  const interp::ModifiedBI* built_solver() const { return solver_ ? &*solver_ : nullptr; }
  const interp::Phong* built_phong() const { return phong_ ? &*phong_ : nullptr; }
  double precompute_ms() const { return precompute_ms_; }
  double phong_ms() const { return phong_ms_; }

  /// Changes modified-BI's alpha (interp checks it) and refactorises if the solver is built.
  void set_alpha(double alpha);

 private:
  Eigen::MatrixXd U_;
  Eigen::MatrixXi T_;
  interp::Options options_;
  std::optional<interp::ModifiedBI> solver_;
  std::optional<interp::Phong> phong_;
  double precompute_ms_ = 0, phong_ms_ = 0;
};

}  // namespace mbi::pipeline
