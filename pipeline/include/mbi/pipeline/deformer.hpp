#pragma once
// Bind once, deform many: the map from the positions X of a control mesh to the positions of
// dense points embedded in it, for one rest control mesh and one set of points. The constructor
// embeds the points and runs the method's precompute (modified-BI's factorisation, Phong's
// weights) once; each pose then costs M, the element Bezier points and one evaluation. The
// Python package's mbi.Deformer is this class.
//
//   pipeline::Deformer deformer(U, T, P, {.method = pipeline::Method::ModifiedBI});
//   deformer.deform(X, positions);            // per pose: p x d positions (exact, double)
//   Eigen::MatrixXd dX = deformer.vjp(G);     // dL/dX (n x d) from G = dL/dpositions (p x d)
//
// Shapes and units: U, X n x d (d = 2 or 3), T m x (d+1) (0-based vertex indices), P,
// positions, normals and G p x d; a batch stacks frames: (frames n) x d poses, (frames p) x d
// results. Positions are in the units of U and X (any units: every map here is scale-free),
// normals are unit vectors, M ((n d) x d) is dimensionless, G is in units of L per unit of
// position and vjp() returns the same.
//
// The positions are a fixed linear map of X for every method (modified-BI: M is linear in X,
// docs/method.md fact 11), so vjp() is exact and the same at every pose: one transpose
// evaluation, the transpose of the Bezier points and, for modified-BI, one solve with the cached
// factor (mbi/interp/adjoint.hpp).
//
// deform() and vjp() are const and may run on several threads at once: each call takes the
// temporaries of the mesh's size (M, the Bezier points, their transposes) from a pool the Deformer
// keeps, so after the first call on a thread they allocate nothing of the mesh's or the points'
// size. deform_float() and set_alpha() change state: not for several threads at once.
#include <mbi/interp/adjoint.hpp>
#include <mbi/interp/fast_evaluate.hpp>
#include <mbi/interp/phong.hpp>
#include <mbi/pipeline/method.hpp>

#include <memory>

namespace mbi::pipeline {

struct DeformerOptions {
  Method method = Method::ModifiedBI;
  interp::Options interp = {};  ///< alpha, beta, pin_boundary, solve path (modified-BI; the others ignore it)
  int threads = 0;         ///< evaluation threads (>= 0), 0 = all cores
};

class Deformer {
 public:
  /// Embeds the dense rest points P (p x d) in the rest control mesh (U, T) and precomputes the
  /// method, the two at once on two threads unless options.threads is 1. rest_normals: p x d unit normals for the deform() calls with normals, or empty.
  /// Throws mbi::Error on an invalid mesh, point, option or size.
  Deformer(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
           const Eigen::Ref<const Eigen::MatrixXd>& P, const DeformerOptions& options = {},
           const Eigen::MatrixXd& rest_normals = Eigen::MatrixXd());
  /// The same with an embedding made before (interp::embed(U, T, P)).
  Deformer(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
           interp::Embedding embedding, const DeformerOptions& options = {},
           const Eigen::MatrixXd& rest_normals = Eigen::MatrixXd());
  ~Deformer();
  Deformer(Deformer&&) noexcept;
  Deformer& operator=(Deformer&&) noexcept;

  int dim() const;
  int vertices() const;       ///< n
  int elements() const;       ///< m
  long long points() const;   ///< p
  Method method() const;
  const DeformerOptions& options() const;
  const interp::Embedding& embedding() const;
  const Eigen::MatrixXd& rest_positions() const;  ///< U
  const Eigen::MatrixXi& elements_matrix() const; ///< T
  bool has_rest_normals() const;
  /// Modified-BI's precompute; Error for the other methods.
  const interp::ModifiedBI& solver() const;
  /// Phong's weights; Error for the other methods.
  const interp::Phong& phong() const;
  /// Changes modified-BI's alpha (> 0) and refactors; Error for the other methods.
  void set_alpha(double alpha);

  /// The method's M at pose X: (n d) x d, 0 for BI. Throws Error on a size mismatch or NaN.
  interp::VertexMatrices M(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  /// The element Bezier points at pose X: (m K) x d (interp::BezierPoints).
  interp::BezierPoints bezier(const Eigen::Ref<const Eigen::MatrixXd>& X) const;

  /// Positions (p x d, exact double) at pose X, into caller memory of that shape.
  void deform(const Eigen::Ref<const Eigen::MatrixXd>& X, interp::PointsRef<double> positions) const;
  /// Positions and mapped unit normals (needs rest normals).
  void deform(const Eigen::Ref<const Eigen::MatrixXd>& X, interp::PointsRef<double> positions,
              interp::PointsRef<double> normals) const;
  Eigen::MatrixXd deform(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  /// Frames at once: X (frames n) x d, positions (frames p) x d; frame k = rows [k n, k n + n).
  /// The same positions as deform() frame by frame; modified-BI solves for M a block of frames at
  /// a time (interp::ModifiedBI::solve_batch: 8 frames on the dense operator, 8 / d on the
  /// factor), so its scratch holds a block's M, not the batch's.
  void deform_batch(const interp::ConstPointsRef<double>& X, interp::PointsRef<double> positions) const;

  /// The float kernel (interp::FastEvaluator, built on the first call): positions, and normals
  /// (needs rest normals), as row-major p x d floats (interleaved xyz, a GPU buffer's layout).
  void deform_float(const Eigen::Ref<const Eigen::MatrixXd>& X, Eigen::Ref<interp::RowMatrixXf> positions);
  void deform_float(const Eigen::Ref<const Eigen::MatrixXd>& X, Eigen::Ref<interp::RowMatrixXf> positions,
                    Eigen::Ref<interp::RowMatrixXf> normals);

  /// dL/dX (n x d) from G = dL/dpositions (p x d): the transpose of deform(), exact. Throws
  /// Error on a size mismatch or a non-finite G.
  Eigen::MatrixXd vjp(const interp::ConstPointsRef<double>& G) const;
  /// Frames at once: G (frames p) x d, out (frames n) x d.
  void vjp_batch(const interp::ConstPointsRef<double>& G, interp::PointsRef<double> out) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  void attach(interp::Embedding embedding, const Eigen::MatrixXd& rest_normals);  // checked, after the precompute
};

}  // namespace mbi::pipeline
