#pragma once
// The memory a scene or a command's run needs, checked before anything large is allocated
// (docs/limits.md): no cap on the sizes, a refusal only when the estimate does not fit.
//
// The per-run cost is dominated by the control mesh: the modified-BI precompute factors a
// sparse matrix over the control vertices, whose size the symbolic analysis gives beforehand
// (interp::estimate_memory; the cost model in docs/performance.md), and the simulator assembles
// 12 x 12 blocks per tetrahedron. The dense model costs memory in proportion to its vertex count.
// Counts are 64-bit throughout.
#include <mbi/interp/memory.hpp>

#include <Eigen/Dense>
#include <cstdint>
#include <string>

namespace mbi::scenes {

/// A floor of a run's memory from its counts alone (d = 2 or 3), far below the estimate: the
/// control mesh, the m-block (at least d^2 entries for each vertex and its d + 1 neighbours of an
/// element) and the simulator's blocks, the dense points. For refusing absurd sizes before a mesh
/// of them is built or generated; the estimate itself needs the mesh.
double minimum_run_bytes(long long dense_vertices, long long control_vertices, long long control_elements, int d);

/// "": fits; else why not ("needs at least X GiB, more than the Y GiB this process may take"):
/// minimum_run_bytes against interp::usable_memory_bytes().
std::string over_memory_floor(long long dense_vertices, long long control_vertices, long long control_elements, int d);

/// The estimate of a run (interp::estimate_memory of the control mesh U, T with `options` and
/// `dense_vertices` points; with `simulation`, plus the simulator's assembly), refused with
/// interp::check_memory against interp::memory_limit(options.max_memory) (an Error starting with
/// `where` that names the sizes) when it would not fit. Returns the estimate.
interp::MemoryEstimate check_run_size(const std::string& where, long long dense_vertices, const Eigen::MatrixXd& U,
                                      const Eigen::MatrixXi& T, const interp::Options& options = {},
                                      bool simulation = false);

}  // namespace mbi::scenes
