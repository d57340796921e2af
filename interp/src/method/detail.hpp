#pragma once
// Internal helpers of mbi::interp (not installed).
#include <mbi/interp/embed.hpp>
#include <mbi/interp/mesh.hpp>
#include <mbi/interp/modified_bi.hpp>

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <span>
#include <string>
#include <vector>

namespace mbi::interp::detail {

/// Throws Error unless U is n x d (d in {2,3}) and T is m x (d+1) with indices in [0, n).
/// Cheaper than validate_mesh (no degeneracy test).
void check_shapes(const Eigen::Ref<const Eigen::MatrixXd>& U,
                  const Eigen::Ref<const Eigen::MatrixXi>& T);

/// The Bezier points B ((m K) x d) of the elements T from X (n x d) and, when M is not null,
/// modified-BI's M ((n d) x d) at rest positions U (fact 5); M null: BI's edge midpoints. Shapes
/// and indices checked by the caller. On the library's threads (bezier_kernel.cpp). listed: the
/// rows of `elements` only (checked by the caller), the others left as they are.
void bezier_rows(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                 const Eigen::Ref<const Eigen::MatrixXd>& X, const MatrixIn* M, MatrixOut B,
                 std::span<const int> elements = {}, bool listed = false);

/// Throws Error naming the first non-finite entry of A (row `what` r).
void check_finite(const char* what, const Eigen::Ref<const Eigen::MatrixXd>& A);

/// Throws Error naming the first entry of `list` (named `what`) outside [0, count).
void check_index_list(const char* what, std::span<const int> list, long long count);

/// Throws Error naming the first of `points` outside emb's points, or whose element is outside
/// [0, elements): the index lists of the subset evaluation and its transpose.
void check_point_list(const Embedding& emb, std::span<const Eigen::Index> points, long long elements);

/// Per-component quadratic forms (method.md facts 1-3), unweighted, energy = z^T H z:
/// vibr_mm (dn x dn), disc_mm (dn x dn), disc_mx (dn x n), disc_xx (n x n); m index i d + r.
struct Hessians {
  Eigen::SparseMatrix<double> vibr_mm, disc_mm, disc_mx, disc_xx;
};
Hessians assemble(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T);

/// Gauge treatment (fact 4). free_vertex(i) = 1 when m_i are unknowns. Returns, per full m
/// index (i d + r), 1 when that unknown must be pinned to zero to remove the gauge null space
/// (t + S u_i on every face-connected component, restricted to what the fixed vertices leave);
/// null_dim receives the number of removed null vectors.
std::vector<char> gauge_pins(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T,
                             const std::vector<char>& free_vertex, int& null_dim);

}  // namespace mbi::interp::detail
