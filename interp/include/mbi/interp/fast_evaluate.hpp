#pragma once
// The compact float evaluation kernel: the fewest bytes per point, every core, no allocation per
// call.
//
// Per point it reads a packed record of 4 (d+1) bytes (element id as int32, then the barycentric
// coordinates b_1..b_d as float; b_0 = 1 - b_1 - ... - b_d) and writes d floats, interleaved
// (x0 y0 z0 x1 y1 z1 ...: a row-major p x d matrix, the layout a GPU vertex buffer takes). In 3D
// that is 16 B in and 12 B out, 28 B a point; with normals also the rest normal (12 B, kept as
// cof(A)^T n, A the element's basis gradients) in and the mapped normal (12 B) out. Per call it
// turns the element Bezier points into each element's quadratic in (b_1..b_d), in float, once
// per element; a point then costs 10 multiply-adds in 3D (on x86 two points to a 512-bit vector
// (AVX-512), or one point and two terms to a 256-bit vector, two points with normals (AVX2)), and
// its normal 6 more for the derivatives D_k = dx/db_k, then cof(D) (cof(A)^T n), renormalised.
// Threads: OpenMP when the build has it. Kernels: picked once per evaluator from the vector
// instructions the CPU has (Simd), or asked for.
//
// Point order: points in random order over element terms larger than a cache (over 16 MiB: about
// 131K tetrahedra) would read each point's terms from memory. Then the evaluator keeps its
// records sorted by element (a stable sort at construction; the permutation costs 4 B a point)
// and writes each result to its point's own row. Records in element order (so sorted, or stored
// so) have their positions computed block by block: a block of elements' terms into a buffer of
// the thread, then the records of those elements, so that no table of every element's terms is
// written and read back (fused_terms()). A point's position and normal are the same bits
// in any order, on any thread count (the last points of a range run as a whole group, as the
// others).
//
// Results agree with interp::evaluate<double> to float round-off (a few ulp of the coordinate
// magnitudes: tests/interp/test_fast_evaluate.cpp states the bound). interp::evaluate<double>
// stays the exact path (files, tests).
#include <mbi/base/names.hpp>
#include <mbi/interp/embed.hpp>
#include <mbi/interp/modified_bi.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mbi::interp {

/// p x d float, row-major: point i's coordinates are contiguous (interleaved xyz).
using RowMatrixXf = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// The vector instructions of an evaluator's kernels (3D; 2D embeddings always run Portable).
/// Every kernel sums in the same order, so each gives the same positions with and without normals.
/// The two x86 kernels give the same positions (up to the sign of a zero: the same fused
/// multiply-adds); the portable loop (separate multiplies and adds) and, with normals, any two
/// kernels differ by float round-off.
enum class Simd {
  Auto,      ///< the widest the CPU has (what the constructor picks by default)
  Avx512,    ///< AVX-512 F, DQ and VL (with AVX2 and FMA): two points to a 512-bit vector
  Avx2,      ///< AVX2 and FMA: one point (positions) or two (with normals) to a 256-bit vector
  Portable,  ///< plain C++, any CPU
};
inline constexpr auto kSimdNames = name_table<Simd>(
    {{Simd::Auto, "auto"}, {Simd::Avx512, "avx512"}, {Simd::Avx2, "avx2"}, {Simd::Portable, "portable"}});

class FastEvaluator {
 public:
  /// Packs emb (element ids, float barycentric coordinates) and, for normals, its per-element
  /// basis gradients. threads = 0: all cores (OpenMP's default team size); 1 = serial. simd: the
  /// kernels (Auto: the widest this CPU has). Throws Error on an inconsistent embedding or a simd
  /// the CPU lacks (supported() tells).
  explicit FastEvaluator(const Embedding& emb, int threads = 0, Simd simd = Simd::Auto);

  /// Whether this CPU (and build) can run the kernels of s (Auto and Portable: always).
  static bool supported(Simd s);
  /// "avx512", "avx2", "portable" (or "auto").
  static const char* name(Simd s);
  /// The kernels this evaluator runs (never Auto; Portable for 2D).
  Simd simd() const { return simd_; }

  /// Rest normals (p x d, unit) for evaluate(B, positions, normals); kept per point as float
  /// m = cof(A)^T n (A: the element's basis gradients), scaled by a power of 2.
  void set_rest_normals(const Eigen::Ref<const Eigen::MatrixXd>& normals);

  int dim() const { return d_; }
  long long size() const { return p_; }
  int elements() const { return m_; }
  /// Threads evaluate() uses.
  int threads() const;
  /// True when most records follow a record of the same element (a mesh's order, or points
  /// sorted by element): the kernel then runs without prefetching the element terms.
  bool coherent() const { return coherent_; }
  /// True when the records are the points sorted by element (see Point order above): results
  /// are scattered to the points' rows.
  bool sorted_by_element() const { return !order_.empty(); }
  /// True when evaluate() without normals computes the element terms block by block, each
  /// block just before the records of its elements, in a buffer of each thread that stays in
  /// cache: the records are in element order (stored so, or sorted_by_element()) and
  /// set_fused_terms() left it on. Otherwise (and always with normals, whose scale needs every
  /// element's terms first) each call writes every element's terms to a table, then reads them
  /// back per point. Both give the same bits.
  bool fused_terms() const { return fuse_ && ordered_ && p_ > 0; }
  /// Turns the fused pass off (false) or back on (true, the default), e.g. to compare the two.
  void set_fused_terms(bool on) { fuse_ = on; }
  bool has_rest_normals() const { return !normals_.empty(); }
  /// Bytes a point reads and writes (STREAM convention): 4 (d+1) in + 4 d out, plus 8 d with
  /// normals.
  int bytes_per_point(bool normals) const { return 4 * (d_ + 1) + 4 * d_ + (normals ? 8 * d_ : 0); }

  /// Positions from B ((m K) x d, interp::BezierPoints layout; read where it is, e.g. a numpy
  /// array). `positions` is resized to p x d
  /// when its shape differs (no allocation when the same matrix is passed every frame).
  void evaluate(const MatrixIn& B, RowMatrixXf& positions);
  /// Positions and mapped normals (cof(J) n, renormalised; 0 where J is singular), as
  /// interp::evaluate does. Needs set_rest_normals().
  void evaluate(const MatrixIn& B, RowMatrixXf& positions, RowMatrixXf& normals);
  /// Same into caller memory (e.g. a mapped GPU buffer): positions and normals (nullptr: no
  /// normals) each hold size() * dim() floats, 16-byte aligned for the fastest (streaming) stores.
  void evaluate(const MatrixIn& B, float* positions, float* normals);

 private:
  void check(const MatrixIn& B, bool normals) const;
  void prepare(const MatrixIn& B, bool normals);
  void evaluate_fused(const MatrixIn& B, float* positions);
  void plan_fused();
  // records a group of the fused pass's kernel takes: 4 with the x86 kernels, 1 with the portable loop
  long long fuse_group() const { return simd_ == Simd::Portable ? 1 : 4; }
  const float* rest_normals_for(const float* positions, const float* normals);
  // the point (input row, output row) of record k
  Eigen::Index point(long long k) const { return order_.empty() ? k : order_[static_cast<size_t>(k)]; }
  static constexpr std::size_t kSlack = 1024;  // floats (4 KiB) to move the rest-normal block in
  static constexpr std::size_t kPad = 48;      // floats after the last record's: the x86 kernels' last group (16 points) reads them

  int d_ = 3, m_ = 0, threads_ = 0;
  Simd simd_ = Simd::Portable;
  bool coherent_ = false;              // most points follow a point of the same element
  bool ordered_ = false;               // every record's element at least the one before's
  bool fuse_ = true;                   // fused_terms() allowed
  float dscale_ = 1.0f;                // per call: a power of 2 near 1 / max |dx/db_k| (normals)
  long long p_ = 0;
  std::vector<std::int32_t> records_;  // (p + padding) (d+1) words a record: element id, then d float bit patterns
  std::vector<std::int32_t> order_;    // p + padding: the point of each record (a stable sort by element); empty: record i is point i
  std::vector<double> grads_;          // m d d: rows 1..d of each element's basis gradients
  std::vector<float> normals_;         // p d from moff_ (+ padding): m = cof(A)^T n per record (AVX-512: 16-record groups by component)
  std::size_t moff_ = 0;               // where normals_'s block starts, in floats
  int moves_ = 0;                      // times the block was moved (at most 2)
  std::vector<long long> fuse_ends_;   // the fused pass's ranges of records (plan_fused())
  std::vector<std::size_t> fuse_first_;  // per block of records, its first range in fuse_ends_
  std::vector<float> coef_;            // m x 32 (3D; 2D: 16): position terms, cache-line aligned, per call (layout: see src/evaluate/fast_kernel.hpp)
};

}  // namespace mbi::interp
