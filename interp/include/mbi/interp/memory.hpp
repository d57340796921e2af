#pragma once
// The peak memory of a modified-BI run, estimated before any numeric work: from the symbolic
// analysis of the Cholesky factor of the m-block (CHOLMOD's, on the control mesh's vertex graph)
// and the sizes that the precompute, the embedding and the evaluation allocate. A caller refuses
// a size that would not fit, naming the sizes, instead of failing in the middle of the
// factorization (docs/performance.md, "Memory").
//
//   const interp::MemoryEstimate e = interp::estimate_memory(U, T, P.rows());
//   interp::check_memory(e, interp::parse_memory_size("8G"), "--max-memory", "cage.node");
#include <mbi/interp/modified_bi.hpp>
#include <mbi/interp/system_memory.hpp>

#include <Eigen/Dense>
#include <string>

namespace mbi::interp {

/// The parts of an estimate: counts, and bytes where the name says bytes.
struct MemoryEstimate {
  long long unknowns = 0;         ///< d n: rows of the m-block (before the few gauge pins)
  long long matrix_nonzeros = 0;  ///< entries of the m-block's pattern, both triangles
  long long factor_nonzeros = 0;  ///< values L stores (CHOLMOD's supernodes with their padding)
  double factor_flops = 0;        ///< floating-point operations of the numeric factorization
  std::string ordering;           ///< the ordering analysed: "AMD", "METIS" or "AMD (Eigen)"
  double factor_bytes = 0;        ///< L's values and row indices, kept for every solve
  double assembly_bytes = 0;      ///< the sparse matrices alive while the factor is computed
  double dense_operator_bytes = 0;  ///< -H^-1 H_mx when the dense solve path is chosen, else 0
  double model_bytes = 0;         ///< dense points, their embedding, the frame's outputs, Bezier points
  double process_bytes = 0;       ///< code, libraries and thread stacks
  double peak_bytes = 0;          ///< the estimated peak resident memory of the whole run
};

/// The estimate for the precompute of the rest control mesh (U n x d, T m x (d+1), d = 2 or 3)
/// with `options` (its solve path and factorization count) and the evaluation of `dense_points`
/// points a frame (>= 0). An upper bound of the factor's stored values on meshes whose vertex
/// blocks are full (the ordering is that of the vertex graph, which CHOLMOD's AMD also finds on
/// the m-block); the peak an upper bound within 13% of the measured one from 1,000 to 140,000
/// control vertices (docs/performance.md, "Memory"). Throws Error on shapes other than those or on indices out of range.
/// Cost: the vertex graph (O(m) pairs, sorted) and one symbolic analysis of it (n vertices: AMD,
/// and METIS from 10,000 unknowns as the factorization does) with CHOLMOD; without CHOLMOD one
/// numeric factorization of the n x n vertex graph with Eigen (about 1/27 of the real one's flops).
/// No numeric work on the m-block; memory O(n + the vertex graph's entries).
MemoryEstimate estimate_memory(const Eigen::Ref<const Eigen::MatrixXd>& U,
                               const Eigen::Ref<const Eigen::MatrixXi>& T, long long dense_points,
                               const Options& options = {});

/// "8G", "512M", "1.5GiB", "300MB", "2e9" -> bytes (K, M, G, T: powers of 1024, with or without
/// "B" or "iB"; a plain number is bytes). Throws Error naming `text` unless it is such a number
/// and > 0.
double parse_memory_size(const std::string& text);

/// "1.23 GiB": bytes for messages.
std::string format_bytes(double bytes);

/// Throws Error when e.peak_bytes exceeds `limit` (bytes; <= 0: no check). The message starts
/// with `where`, gives the estimate and its largest parts (the factor's nonzeros and bytes, the
/// unknowns), the limit and its source (`limit_name`: "--max-memory", "MemAvailable", ...).
void check_memory(const MemoryEstimate& e, double limit, const std::string& limit_name, const std::string& where);

}  // namespace mbi::interp
