#pragma once
// Transposes (vector-Jacobian products) of the linear maps from control positions to dense
// points. For every method the dense positions are a fixed linear map of X (BI: M = 0;
// Phong: M linear in X; modified-BI: M solved linearly from X, docs/method.md fact 11):
//
//   X -> M (ModifiedBI::solve, Phong::M) -> B (bezier_points) -> positions (evaluate)
//
// so dL/dX for a loss L on the positions is exact and independent of the pose:
//
//   GB = evaluate_transpose(emb, G, m)          dL/dB from G = dL/dpositions
//   auto [GX, GM] = bezier_transpose(U, T, GB)  dL/dX through B directly, and dL/dM
//   GX += solver.solve_transpose(GM)            (modified-BI; Phong: phong.M_transpose(GM))
//
// Shapes as in mbi::interp: U, X n x d, T m x (d+1), G p x d, B (m K) x d, M (n d) x d.
#include <mbi/interp/embed.hpp>
#include <mbi/interp/evaluate.hpp>
#include <mbi/interp/modified_bi.hpp>

namespace mbi::interp {

/// The transpose of evaluate<double>(): dL/dB ((m K) x d, the BezierPoints layout) from
/// G = dL/dpositions (p x d) for the points of emb in a mesh of m elements. Each point adds its
/// Bernstein weights times its row of G to its element's K rows. threads = 0: all cores; the
/// sums run in an order fixed by the thread count. Throws Error on mismatched sizes, an element
/// outside [0, m), or a non-finite G (named by its row).
BezierPoints evaluate_transpose(const Embedding& emb, const ConstPointsRef<double>& G, int elements,
                                int threads = 0);
/// The same into caller memory out ((m K) x d already, Error otherwise); its per-thread sums are
/// kept per calling thread, so after the first call on a thread it allocates nothing.
void evaluate_transpose(const Embedding& emb, const ConstPointsRef<double>& G, int elements,
                        Eigen::Ref<BezierPoints> out, int threads = 0);

/// The transpose of the subset evaluate() (evaluate.hpp): dL/dB into out ((m K) x d already)
/// from G (|points| x d, row i for point points[i]), on the K rows of each listed point's element
/// only (set to their sums); the other rows, zero in the transpose, are left as they are (read
/// them through the same elements: bezier_transpose's list). Each run of consecutive listed
/// points of one element is summed in list order and the runs added in order, so the result is
/// the same to the bit for every thread count. Costs the listed points. Throws Error as the full
/// transpose does, and on an index outside [0, p).
void evaluate_transpose(const Embedding& emb, std::span<const Eigen::Index> points, const ConstPointsRef<double>& G,
                        int elements, Eigen::Ref<BezierPoints> out, int threads = 0);

/// The two parts of the transpose of bezier_points(U, T, X, M).
struct BezierTranspose {
  Eigen::MatrixXd X;  ///< n x d: dL/dX through B directly (for BI, M = 0, all of dL/dX)
  VertexMatrices M;   ///< (n d) x d: dL/dM
};

/// The transpose of bezier_points() (and of bezier_bi(), whose transpose is the X part) from
/// G = dL/dB ((m K) x d). Throws Error on mismatched sizes.
BezierTranspose bezier_transpose(const Eigen::Ref<const Eigen::MatrixXd>& U,
                                 const Eigen::Ref<const Eigen::MatrixXi>& T, const BezierPoints& G);
/// The same into caller memory: X (n x d) and M ((n d) x d), of those sizes already.
void bezier_transpose(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                      const Eigen::Ref<const BezierPoints>& G, Eigen::Ref<Eigen::MatrixXd> X,
                      Eigen::Ref<VertexMatrices> M);
/// The same from the listed elements' rows of G only, added in list order (G's other rows are
/// not read): with the list ascending, duplicate-free and G zero elsewhere, the full transpose
/// to the bit. Costs the listed elements and zeroing X and M. Error also on an element outside
/// [0, m).
void bezier_transpose(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                      const Eigen::Ref<const BezierPoints>& G, std::span<const int> elements,
                      Eigen::Ref<Eigen::MatrixXd> X, Eigen::Ref<VertexMatrices> M);

}  // namespace mbi::interp
