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
#include <filesystem>
#include <string>

namespace mbi::scenes {

/// A floor of a run's memory from its counts alone (d = 2 or 3), far below the estimate: the
/// control mesh, the m-block (at least d^2 entries for each vertex and its d + 1 neighbours of an
/// element) and the simulator's blocks, the dense points. For refusing absurd sizes before a mesh
/// of them is built or generated; the estimate itself needs the mesh.
double minimum_run_bytes(long long dense_vertices, long long control_vertices, long long control_elements, int d);

/// "": fits; else why not ("needs at least X GiB, more than the Y GiB this process may take"):
/// minimum_run_bytes against usable_memory_bytes().
std::string over_memory_floor(long long dense_vertices, long long control_vertices, long long control_elements, int d);

/// Physical memory of this machine in bytes (sysconf), or 0 when unknown.
double physical_memory_bytes();

/// The memory limit of the control group a process is in, in bytes, or 0 when there is none:
/// the smallest `memory.max` (cgroup v2) or `memory.limit_in_bytes` (v1) on its path and the
/// paths above it. `proc_self_cgroup` is the text of /proc/self/cgroup; `root` the cgroup mount
/// (/sys/fs/cgroup: v2 there or under unified/, v1 under memory/). Unreadable files count as no
/// limit; "max" and v1's "unlimited" (>= 2^60) too.
double cgroup_memory_limit(const std::string& proc_self_cgroup, const std::filesystem::path& root);

/// The memory this process may use: the physical memory, or its control group's limit when that
/// is smaller (a container). 0 when unknown.
double usable_memory_bytes();

/// The memory this run may take: `max_memory` when > 0 (named "--max-memory"), else the smaller
/// of MemAvailable (interp::available_memory_bytes) and usable_memory_bytes(); `name` receives
/// what it is. 0 when unknown.
double memory_limit(double max_memory, std::string& name);

/// The estimate of a run (interp::estimate_memory of the control mesh U, T with `options` and
/// `dense_vertices` points; with `simulation`, plus the simulator's assembly), refused with
/// interp::check_memory against memory_limit(max_memory) (an Error starting with `where` that
/// names the sizes) when it would not fit. Returns the estimate.
interp::MemoryEstimate check_run_size(const std::string& where, long long dense_vertices, const Eigen::MatrixXd& U,
                                      const Eigen::MatrixXi& T, double max_memory = 0,
                                      const interp::Options& options = {}, bool simulation = false);

}  // namespace mbi::scenes
