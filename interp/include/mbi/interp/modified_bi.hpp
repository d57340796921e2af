#pragma once
// Modified barycentric interpolation (Huang, Chen, Liu, Bao 2008), see docs/method.md.
//
//   x(u) = sum_i phi_i(u) (x_i + M_i (u - u_i))
//
// Precompute once per rest mesh and parameters (ModifiedBI constructor): assemble E_vibr and
// E_disc on the per-component unknowns m (d n of them, method.md fact 1), choose beta (fact 7),
// remove the gauge null space (fact 4) and factor. Per frame: solve() gives all M_i for the
// deformed positions X, bezier() the element control points that evaluate() consumes.
#include <mbi/base/names.hpp>
#include <mbi/interp/mesh.hpp>

#include <Eigen/SparseCore>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace mbi::interp {

/// How solve() maps X to M (fact 11): sparse triangular solves with the cached Cholesky factor,
/// one dense product with the precomputed operator -H_mm^-1 H_mx ((d n) x n doubles), or, with
/// no factor at all, preconditioned conjugate gradients warm-started from the calling thread's
/// previous solve, accurate to 1e-6 of the model size (fact 19). Automatic picks the dense
/// operator for small meshes (see modified_bi.cpp for the measured threshold), the iterative path
/// when the factor's memory estimate exceeds the memory available, and the sparse path otherwise.
enum class SolvePath { Automatic, Sparse, Dense, Iterative };
inline constexpr auto kSolvePathNames =
    name_table<SolvePath>({{SolvePath::Automatic, "automatic"}, {SolvePath::Sparse, "sparse"},
                           {SolvePath::Dense, "dense"}, {SolvePath::Iterative, "iterative"}});

/// Which sparse Cholesky factorization the precompute runs (the result is the same up to
/// round-off): Eigen's SimplicialLLT with AMD (always built), or CHOLMOD's supernodal
/// factorization with the better of AMD and METIS orderings (when the build has CHOLMOD:
/// cholmod_available()). Automatic = CHOLMOD when available.
enum class Factorization { Automatic, Eigen, Cholmod };
inline constexpr auto kFactorizationNames = name_table<Factorization>(
    {{Factorization::Automatic, "automatic"}, {Factorization::Eigen, "eigen"}, {Factorization::Cholmod, "cholmod"}});

/// True when this build of interp has CHOLMOD (CMake MBI_WITH_CHOLMOD, libsuitesparse-dev).
bool cholmod_available();

struct Options {
  std::optional<double> alpha = std::nullopt;  ///< weight of E_vibr; unset: default_alpha(d); check_alpha() bounds it
  double beta = 0.0;          ///< weight of E_disc; 0 = automatic (equal Frobenius norms, fact 7); < 0 rejected
  bool pin_boundary = false;  ///< M_i = 0 on boundary vertices (fact 9)
  SolvePath solve_path = SolvePath::Automatic;
  Factorization factorization = Factorization::Automatic;  ///< Cholmod without CHOLMOD: Error
  /// Iterative path: most PCG iterations a solve may take before it throws Error (0: 20000).
  int max_iterations = 0;
  /// Bytes the run may take (0: memory_limit's default, MemAvailable or the control group's
  /// limit): SolvePath::Automatic takes the iterative path when the factor's estimated peak
  /// exceeds it. check_max_memory() bounds it.
  double max_memory = 0;
};

/// Default alpha for dimension d (0.1 in 3D, 0.2 in 2D).
double default_alpha(int d);
/// The one check of alpha: returns it, or throws Error unless it is finite and > 0 (E_disc alone
/// has extra null modes).
double check_alpha(double alpha);
/// The alpha that options give in dimension d: options.alpha (checked), or default_alpha(d).
double resolve_alpha(const Options& options, int d);
/// beta's check: throws Error unless options.beta is finite and >= 0 (0 = automatic).
void check_beta(const Options& options);
/// max_memory's check: throws Error unless options.max_memory is finite and >= 0.
void check_max_memory(const Options& options);

/// Per-vertex matrices M: (n d) x d; rows [i d, i d + d) hold M_i (d x d). Row c of M_i is m_i
/// of output component c.
using VertexMatrices = Eigen::MatrixXd;

/// Element Bezier control points: (m * K) x d with K = (d+1)(d+2)/2 per element; element e
/// uses rows [e K, e K + K): first the d+1 vertex points x_i (local order of T), then the edge
/// points P_ij for local pairs in the order of bezier_edges(d).
using BezierPoints = Eigen::MatrixXd;

/// Caller memory of any positive strides (a numpy array in C or Fortran order, a block), which
/// the out-variants write (MatrixOut) or read (MatrixIn) where it is, without a copy.
using MatrixOut = Eigen::Ref<Eigen::MatrixXd, 0, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>>;
using MatrixIn = Eigen::Ref<const Eigen::MatrixXd, 0, Eigen::Stride<Eigen::Dynamic, Eigen::Dynamic>>;

/// Local vertex pairs (i<j) of the edge control points: 3 in 2D, 6 in 3D.
const std::vector<std::pair<int, int>>& bezier_edges(int d);

class ModifiedBI {
 public:
  /// Precompute for rest mesh (U n x d, T m x (d+1)). Validates the mesh (throws Error, also for
  /// a mesh without interior faces). Automatic beta = ||H_vibr,mm||_F / ||H_disc,mm||_F over
  /// the full m-blocks (independent of alpha and of pin_boundary). Cost: dominated by the sparse
  /// Cholesky factorisation (see Factorization; figures in docs/performance.md) and, on the
  /// dense path, by the n solves that build the operator.
  ModifiedBI(const Eigen::Ref<const Eigen::MatrixXd>& U,
             const Eigen::Ref<const Eigen::MatrixXi>& T, const Options& options = {});
  ~ModifiedBI();
  ModifiedBI(ModifiedBI&&) noexcept;
  ModifiedBI& operator=(ModifiedBI&&) noexcept;

  /// Changes alpha (> 0): assembles the Hessians again (O(m)) and refactors; beta stays as
  /// chosen at construction unless automatic (it does not depend on alpha).
  void set_alpha(double alpha);

  int dim() const;
  int vertices() const;
  int elements() const;
  double alpha() const;
  double beta() const;
  bool pin_boundary() const;
  /// Dimension of the gauge null space removed (per output component): d + d(d-1)/2 (6 in 3D,
  /// 3 in 2D) per face-connected part of the mesh, or 0 with pin_boundary. The gauge is fixed by
  /// pinning that many scalar unknowns to 0, chosen by column-pivoted QR of the null vectors
  /// (t + S u_i); x(u) does not depend on the choice. Parts that share a vertex but no face are
  /// rejected (Error).
  int null_space_dim() const;
  /// Number of scalar unknowns per component after pinning (boundary, gauge, unused vertices).
  int unknowns() const;
  /// True when solve() uses the dense operator -H_mm^-1 H_mx.
  bool dense_operator() const;
  /// The path solve() takes: Sparse, Dense or Iterative (never Automatic).
  SolvePath solve_path() const;
  /// The factorization used: "Eigen SimplicialLLT (AMD)", "CHOLMOD supernodal (METIS)", ...; on
  /// the iterative path "none: PCG, incomplete Cholesky (AMD) preconditioner".
  std::string factorization() const;
  /// Iterative path: the PCG iterations of the calling thread's last solve() (the largest over
  /// the d components; of the last pose for solve_batch); 0 on the other paths.
  int iterations() const;
  /// Entries of the Cholesky factor L (of the incomplete one on the iterative path), and the
  /// bytes the precompute keeps (factor, dense operator, the right-hand-side operator, the rest
  /// mesh; on the iterative path the matrix and its preconditioner).
  long long factor_nonzeros() const;
  long long memory_bytes() const;
  /// The factor as stored (sparse and dense paths; 0 on the iterative path): its values (CHOLMOD
  /// keeps whole supernodal blocks: more than factor_nonzeros()) and the bytes of its index
  /// arrays. A sparse solve streams both twice (forward and backward sweep).
  long long factor_stored_values() const;
  long long factor_index_bytes() const;

  /// M for deformed control positions X (n x d). Throws Error on a size mismatch or NaN, and on
  /// the iterative path when PCG does not converge within Options::max_iterations.
  VertexMatrices solve(const Eigen::Ref<const Eigen::MatrixXd>& X) const;
  /// The same into caller memory M ((n d) x d already, Error otherwise). Its temporaries are kept
  /// per thread: after the first call on a thread it allocates nothing.
  void solve(const Eigen::Ref<const Eigen::MatrixXd>& X, MatrixOut M) const;
  /// M of several poses at once: X (frames n) x d, pose k in rows [k n, k n + n), into M
  /// ((frames n d) x d already), pose k's M in rows [k n d, k n d + n d); the same as solve()
  /// pose by pose. solve() is linear column by column in X (fact 11): one pass over the dense
  /// operator, or one solve with the factor for every 8 / d poses, serves all of them. Its
  /// temporaries, kept per thread, grow with the poses of one call: give a few at a time.
  void solve_batch(const MatrixIn& X, MatrixOut M) const;

  /// The transpose of solve(), which is linear in X (fact 11): dL/dX (n x d) from
  /// G = dL/dM ((n d) x d). One solve with the cached factor (the system is symmetric) and one
  /// product with H_mx^T. On the iterative path the solve is PCG from zero, so the result is the
  /// transpose to the solve's tolerance (fact 19), not exactly. Throws Error on a size mismatch
  /// or NaN.
  Eigen::MatrixXd solve_transpose(const VertexMatrices& G) const;
  /// The same into caller memory GX (n x d already); no allocation after the first call on a thread.
  void solve_transpose(const Eigen::Ref<const Eigen::MatrixXd>& G, Eigen::Ref<Eigen::MatrixXd> GX) const;

  /// M's rows of the listed vertices only (each vertex's d rows of M ((n d) x d already); the
  /// others are left as they are), for products that need M near a few elements. On the dense
  /// path those rows of the operator, the same values as solve()'s to the bit, at a cost of
  /// |vertices| d n; the other paths solve for all of M (solve()'s cost). Errors as solve(), and
  /// on a vertex outside [0, n). Allocates nothing after the first call on a thread.
  void solve_vertices(const Eigen::Ref<const Eigen::MatrixXd>& X, std::span<const int> vertices, MatrixOut M) const;
  /// The transpose of solve_vertices(): dL/dX (n x d) from G = dL/dM whose rows outside the listed
  /// vertices are zero. On the dense path it reads only the listed vertices' rows of the operator
  /// (each vertex once, however often listed); the other paths take solve_transpose(). Errors as
  /// solve_transpose(), and on a vertex outside [0, n).
  void solve_transpose_vertices(const Eigen::Ref<const Eigen::MatrixXd>& G, std::span<const int> vertices,
                                Eigen::Ref<Eigen::MatrixXd> GX) const;

  /// Bezier control points for positions X and matrices M (M = 0 gives BI).
  BezierPoints bezier(const Eigen::Ref<const Eigen::MatrixXd>& X, const VertexMatrices& M) const;

  /// The assembled per-component quadratic forms (fact 1): Q(m, x_c) =
  /// [m; x_c]^T [H_mm H_mx; H_mx^T H_xx] [m; x_c] for E_vibr and E_disc separately, unweighted,
  /// m ordered as m_i = (row c of M_i), vertex-major (d n), x_c of size n. For tests & metrics:
  /// each call assembles them anew (O(m)), since the precompute keeps only what solves need.
  Eigen::SparseMatrix<double> vibr_hessian_mm() const;
  Eigen::SparseMatrix<double> disc_hessian_mm() const;
  Eigen::SparseMatrix<double> disc_hessian_mx() const;
  Eigen::SparseMatrix<double> disc_hessian_xx() const;

  const Eigen::MatrixXd& rest_positions() const;
  const Eigen::MatrixXi& elements_matrix() const;

 private:
  void warm_up() const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Bezier control points of plain BI (M = 0) without any precompute.
BezierPoints bezier_bi(const Eigen::Ref<const Eigen::MatrixXd>& X,
                       const Eigen::Ref<const Eigen::MatrixXi>& T);
/// The same into caller memory B ((m K) x d already, Error otherwise).
void bezier_bi(const Eigen::Ref<const Eigen::MatrixXd>& X, const Eigen::Ref<const Eigen::MatrixXi>& T, MatrixOut B);

/// The Bezier points of the listed elements only: their rows of B ((m K) x d already; the other
/// rows are left as they are), the same values as bezier_points()' to the bit. Errors as
/// bezier_points(), and on an element outside [0, m).
void bezier_points(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                   const Eigen::Ref<const Eigen::MatrixXd>& X, const MatrixIn& M, std::span<const int> elements,
                   MatrixOut B);
/// Bezier control points from any M (method.md fact 5); needs rest positions U.
BezierPoints bezier_points(const Eigen::Ref<const Eigen::MatrixXd>& U,
                           const Eigen::Ref<const Eigen::MatrixXi>& T,
                           const Eigen::Ref<const Eigen::MatrixXd>& X, const VertexMatrices& M);
/// The same into caller memory B ((m K) x d already, Error otherwise).
void bezier_points(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                   const Eigen::Ref<const Eigen::MatrixXd>& X, const MatrixIn& M, MatrixOut B);

/// The defining formula x(u) = sum_i phi_i (x_i + M_i (u - u_i)) at rest point u in element e
/// (slow; for tests and reference).
Eigen::VectorXd evaluate_reference(const Eigen::Ref<const Eigen::MatrixXd>& U,
                                   const Eigen::Ref<const Eigen::MatrixXi>& T,
                                   const Eigen::Ref<const Eigen::MatrixXd>& X,
                                   const VertexMatrices& M, int e,
                                   const Eigen::Ref<const Eigen::VectorXd>& u);

}  // namespace mbi::interp
