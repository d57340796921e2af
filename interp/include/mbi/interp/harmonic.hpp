#pragma once
// Harmonic extension over a control mesh: the free nodes' displacement minimising the Dirichlet
// energy of the piecewise-linear displacement field over the rest elements (P1 stiffness, the
// cotangent Laplacian), the fixed nodes' displacement given. At rest every node stays at rest;
// an affine motion of the fixed nodes moves the free ones by the same map (linear precision).
// What a cage's interior nodes do when an artist animates only its boundary.
#include <Eigen/Core>
#include <memory>

namespace mbi::interp {

class HarmonicExtension {
 public:
  /// U: n x d rest nodes, T: m x (d+1) elements (validate_mesh's checks), fixed: indices of the
  /// nodes whose positions are given (any order, no repeats). Free nodes: the others that some
  /// element uses; nodes no element uses are left as given. Cost: one sparse Cholesky factor of
  /// the free block (CHOLMOD when the build has it), O(free nodes) memory beyond its fill.
  /// Throws Error naming the argument or element: bad mesh, an index out of range or repeated,
  /// free nodes not connected through elements to any fixed node.
  HarmonicExtension(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                    const Eigen::Ref<const Eigen::VectorXi>& fixed);
  HarmonicExtension(HarmonicExtension&&) noexcept;
  HarmonicExtension& operator=(HarmonicExtension&&) noexcept;
  ~HarmonicExtension();

  /// X: n x d with the fixed nodes' positions; the free nodes' rows are replaced by U's rows plus
  /// the extension of the fixed nodes' displacement X - U. O(fill) per call, serial, thread-safe.
  void apply(Eigen::Ref<Eigen::MatrixXd> X) const;

  const Eigen::VectorXi& free_nodes() const;   ///< ascending
  const Eigen::VectorXi& fixed_nodes() const;  ///< ascending
  long long memory_bytes() const;              ///< what the object holds

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mbi::interp
