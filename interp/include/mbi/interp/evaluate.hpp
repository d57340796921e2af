#pragma once
// Evaluation of the embedded points from element Bezier control points (method.md facts 5, 6).
// Multithreaded (the library's pool); the same functions serve BI (M = 0) and modified-BI.
//
// Which to use: evaluate() is the one-shot call, nothing to set up. In float and 3D (positions
// only) it runs FastEvaluator's kernels, but packs the embedding on every call, so it is slower
// than FastEvaluator; in double it evaluates the Bernstein form exactly, slower still. A frame
// loop over the same points wants FastEvaluator (fast_evaluate.hpp), which packs the points
// once, or pipeline::CpuEvaluator.
#include <mbi/interp/embed.hpp>
#include <mbi/interp/modified_bi.hpp>

#include <span>

namespace mbi::interp {

/// Positions of all embedded points: p x d. B: the element Bezier points ((m K) x d,
/// interp::BezierPoints' layout) in memory of any strides (a BezierPoints, a numpy array), read
/// where they are in double and in the float 3D positions; converted once for the other float paths. threads = 0: the library's count (set_threads). On the float 3D path a point
/// whose element is not one of B's is found while evaluating: the Error names it, and positions
/// are then partly written; every other error leaves the outputs untouched.
template <typename Scalar>
void evaluate(const MatrixIn& B, const Embedding& emb,
              Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>& positions, int threads = 0);

/// Positions and mapped normals: normals_rest (p x d, unit rest normals) map by cof(J) n and are
/// renormalised (fact 6); a zero mapped normal (singular J) is returned as 0. normals_out is
/// p x d. Needs emb.gradients (filled by embed()); throws Error otherwise.
/// Points outside the mesh (emb.outside) are extrapolated with their element's quadratic.
template <typename Scalar>
void evaluate(const MatrixIn& B, const Embedding& emb,
              const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>& normals_rest,
              Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>& positions,
              Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>& normals_out, int threads = 0);

/// p x d values in caller memory with any strides (a numpy array, one frame of a batch), to
/// write (PointsRef) or to read (ConstPointsRef).
template <typename Scalar>
using PointsRef = Eigen::Ref<Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>, 0,
                             Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>>;
template <typename Scalar>
using ConstPointsRef = Eigen::Ref<const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>, 0,
                                  Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>>;

/// The same two in caller memory: positions (and normals_out) must be p x d already (Error
/// otherwise); nothing of the points' size is allocated.
template <typename Scalar>
void evaluate(const MatrixIn& B, const Embedding& emb, PointsRef<Scalar> positions, int threads = 0);
template <typename Scalar>
void evaluate(const MatrixIn& B, const Embedding& emb, const ConstPointsRef<Scalar>& normals_rest,
              PointsRef<Scalar> positions, PointsRef<Scalar> normals_out, int threads = 0);

/// Positions of the embedded points `points` (indices into emb, any order, repeats allowed), in
/// that order: row i is row points[i] of evaluate<double>(B, emb, ...), to the bit. positions
/// must be |points| x d already. Costs the listed points only. threads as above. Throws Error,
/// before writing, on an index outside [0, p) or a listed point whose element is not one of B's.
void evaluate(const MatrixIn& B, const Embedding& emb, std::span<const Eigen::Index> points,
              PointsRef<double> positions, int threads = 0);

/// Jacobian dx/du (d x d) at one embedded point (element e, barycentric b), needs rest U/T for
/// the basis gradients.
Eigen::MatrixXd jacobian(const Eigen::Ref<const Eigen::MatrixXd>& U,
                         const Eigen::Ref<const Eigen::MatrixXi>& T, const BezierPoints& B, int e,
                         const Eigen::Ref<const Eigen::VectorXd>& bary);

}  // namespace mbi::interp
