#pragma once
// The compact float evaluation kernel (issue 11, target 1): the fewest bytes per point, every
// core, no allocation per call.
//
// Per point it reads a packed record of 4 (d+1) bytes (element id as int32, then the barycentric
// coordinates b_1..b_d as float; b_0 = 1 - b_1 - ... - b_d) and writes d floats, interleaved
// (x0 y0 z0 x1 y1 z1 ...: a row-major p x d matrix, the layout a GPU vertex buffer takes). In 3D
// that is 16 B in and 12 B out, 28 B a point; with normals also the rest normal (12 B) in and the
// mapped normal (12 B) out. Per call it turns the element Bezier points into each element's
// quadratic in (b_1..b_d) (and, for normals, the Jacobian's linear form), in float, once per
// element; the points then cost 9 vector FMAs each in 3D. Threads: OpenMP when the build has it.
//
// Results agree with interp::evaluate<double> to float round-off (a few ulp of the coordinate
// magnitudes: tests/interp/test_fast_evaluate.cpp states the bound). interp::evaluate<double>
// stays the exact path (files, tests).
#include <mbi/interp/embed.hpp>
#include <mbi/interp/modified_bi.hpp>

#include <cstdint>
#include <vector>

namespace mbi::interp {

/// p x d float, row-major: point i's coordinates are contiguous (interleaved xyz).
using RowMatrixXf = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

class FastEvaluator {
 public:
  /// Packs emb (element ids, float barycentric coordinates) and, for normals, its per-element
  /// basis gradients. threads = 0: all cores (OpenMP's default team size); 1 = serial.
  /// Throws Error on an inconsistent embedding.
  explicit FastEvaluator(const Embedding& emb, int threads = 0);

  /// Rest normals (p x d, unit) for evaluate(B, positions, normals); kept as float.
  void set_rest_normals(const Eigen::Ref<const Eigen::MatrixXd>& normals);

  int dim() const { return d_; }
  long long size() const { return p_; }
  int elements() const { return m_; }
  /// Threads evaluate() uses.
  int threads() const;
  bool has_rest_normals() const { return !normals_.empty(); }
  /// Bytes a point reads and writes (STREAM convention): 4 (d+1) in + 4 d out, plus 8 d with
  /// normals.
  int bytes_per_point(bool normals) const { return 4 * (d_ + 1) + 4 * d_ + (normals ? 8 * d_ : 0); }

  /// Positions from B ((m K) x d, interp::BezierPoints layout). `positions` is resized to p x d
  /// when its shape differs (no allocation when the same matrix is passed every frame).
  void evaluate(const BezierPoints& B, RowMatrixXf& positions);
  /// Positions and mapped normals (cof(J) n, renormalised; 0 where J is singular), as
  /// interp::evaluate does. Needs set_rest_normals().
  void evaluate(const BezierPoints& B, RowMatrixXf& positions, RowMatrixXf& normals);
  /// Same into caller memory (e.g. a mapped GPU buffer): positions and normals (nullptr: no
  /// normals) each hold size() * dim() floats, 16-byte aligned for the fastest (streaming) stores.
  void evaluate(const BezierPoints& B, float* positions, float* normals);

 private:
  void prepare(const BezierPoints& B, bool normals);

  int d_ = 3, m_ = 0, threads_ = 0;
  long long p_ = 0;
  std::vector<std::int32_t> records_;  // p (d+1) words: element id, then d float bit patterns
  std::vector<float> grads_;           // m d d: rows 1..d of each element's basis gradients
  std::vector<float> normals_;         // p d (+ padding) rest normals
  std::vector<float> coef_;            // m x 32 (3D; 2D: 16): position terms, cache-line aligned, per call
  std::vector<float> jac_;             // m x 48 (3D; 2D: 16): Jacobian terms, per call with normals
};

}  // namespace mbi::interp
