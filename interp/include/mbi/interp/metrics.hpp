#pragma once
// Quality metrics (paper Table 2, method.md fact 12).
#include <mbi/interp/modified_bi.hpp>

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

struct DiscontinuityTable {
  Summary bi, modified_bi;
  Summary ratio;        ///< bi / modified_bi, field by field (inf when modified_bi is 0)
  double e_vibr = 0;    ///< E_vibr of modified-BI
  double e_disc = 0;    ///< E_disc of modified-BI (= sum of its face energies)
  double e_total = 0;   ///< alpha E_vibr + beta E_disc
  int faces = 0;
};

/// Table 2 for one frame: BI (M = 0) against modified-BI with matrices M from solver.solve(X).
DiscontinuityTable discontinuity_table(const ModifiedBI& solver,
                                       const Eigen::Ref<const Eigen::MatrixXd>& X,
                                       const VertexMatrices& M);

/// E_vibr = sum_t |t| ||Hess x||_F^2 summed over components.
double vibration_energy(const Eigen::Ref<const Eigen::MatrixXd>& U,
                        const Eigen::Ref<const Eigen::MatrixXi>& T, const VertexMatrices& M);

}  // namespace mbi::interp
