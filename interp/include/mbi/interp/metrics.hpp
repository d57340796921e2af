#pragma once
// Quality metrics (paper Table 2, method.md fact 12).
#include <mbi/interp/embed.hpp>
#include <mbi/interp/modified_bi.hpp>

#include <optional>

namespace mbi::interp {

struct Summary {
  double mean = 0, std = 0, max = 0;  ///< std is the population standard deviation
};

/// Per-interior-face discontinuity energy E_F = integral_F ||grad x|_t - grad x|_t'||_F^2 for
/// the field defined by (X, M); one entry per row of interior_faces(T).
Eigen::VectorXd face_discontinuity(const Eigen::Ref<const Eigen::MatrixXd>& U,
                                   const Eigen::Ref<const Eigen::MatrixXi>& T,
                                   const Eigen::Ref<const Eigen::MatrixXd>& X,
                                   const VertexMatrices& M);

Summary summarize(const Eigen::Ref<const Eigen::VectorXd>& values);

/// A metric that does not fit in a double (e.g. energies of deformed positions near 1e300,
/// which grow with their square). Thrown instead of returning inf or NaN.
class OverflowError : public Error {
 public:
  using Error::Error;
};

struct DiscontinuityTable {
  Summary bi, modified_bi;
  Summary ratio;        ///< bi / modified_bi, field by field (inf when modified_bi is 0)
  double e_vibr = 0;    ///< E_vibr of modified-BI
  double e_disc = 0;    ///< E_disc of modified-BI (= sum of its face energies)
  double e_total = 0;   ///< alpha E_vibr + beta E_disc
  int faces = 0;
  /// Phong's column (Phong::M), when the table was asked for with it; phong_ratio = bi / phong.
  std::optional<Summary> phong;
  Summary phong_ratio;
};

/// Table 2 for one frame: BI (M = 0) against modified-BI with matrices M from solver.solve(X).
/// Throws OverflowError when an energy, a summary or E_total is not finite (X or M too large);
/// only the ratios may be inf (a zero denominator), never NaN.
DiscontinuityTable discontinuity_table(const ModifiedBI& solver,
                                       const Eigen::Ref<const Eigen::MatrixXd>& X,
                                       const VertexMatrices& M);

/// The same table with a Phong column: M_phong = Phong::M(X) (phong.hpp), same shape as M.
DiscontinuityTable discontinuity_table(const ModifiedBI& solver,
                                       const Eigen::Ref<const Eigen::MatrixXd>& X,
                                       const VertexMatrices& M, const VertexMatrices& M_phong);

/// Accuracy of an interpolated field against a deformation g known in closed form, over the
/// embedded points. Relative measures, so that models of any size and stiffness compare:
struct Accuracy {
  double position_rms = 0;  ///< sqrt(mean_p |x(u_p) - g(u_p)|^2) / size
  double position_max = 0;  ///< max_p |x(u_p) - g(u_p)| / size
  double gradient_rms = 0;  ///< sqrt(sum_p ||J(u_p) - Dg(u_p)||_F^2 / sum_p ||Dg(u_p)||_F^2)
  double gradient_max = 0;  ///< max_p ||J - Dg||_F / ||Dg||_F
  double size = 0;          ///< model size: diagonal of the rest points' bounding box
};

/// Accuracy of the field given by Bezier points B (any method) at the points of emb (which
/// must have emb.gradients, as embed() fills them). rest: p x d rest points (for the size);
/// exact: p x d, g at the points; exact_gradients: (p d) x d, rows [p d, p d + d) hold Dg at
/// point p (Dg(r, c) = d g_r / d u_c). J is the field's Jacobian dx/du (fact 6), not finite
/// differences. Throws Error on mismatched sizes.
Accuracy accuracy(const BezierPoints& B, const Embedding& emb,
                  const Eigen::Ref<const Eigen::MatrixXd>& rest,
                  const Eigen::Ref<const Eigen::MatrixXd>& exact,
                  const Eigen::Ref<const Eigen::MatrixXd>& exact_gradients);

/// E_vibr = sum_t |t| ||Hess x||_F^2 summed over components.
double vibration_energy(const Eigen::Ref<const Eigen::MatrixXd>& U,
                        const Eigen::Ref<const Eigen::MatrixXi>& T, const VertexMatrices& M);

}  // namespace mbi::interp
