#pragma once
// Resource caps of a scene, checked before anything large is allocated (docs/limits.md).
//
// The per-run cost is dominated by the control mesh: the modified-BI precompute factors a
// sparse matrix over the control vertices (CHOLMOD: 15 s at 10,648 vertices, growing about as
// n^2.5) and the simulator assembles 12 x 12 blocks per tetrahedron. The dense model costs
// memory in proportion to its vertex count. Counts are 64-bit throughout.
#include <cstdint>
#include <filesystem>
#include <string>

namespace mbi::scenes {

/// Most control vertices a scene may have (generated, built-in or read): about a minute of
/// precompute at the cap.
inline constexpr long long kMaxControlVertices = 20000;
/// Most control elements (tetrahedra or triangles) a scene may have.
inline constexpr long long kMaxControlElements = 150000;

/// Estimated peak memory (bytes) of a run with these sizes (d = 2 or 3): positions, embedding
/// and per-frame buffers of the dense model, the assembled control-mesh matrices and an
/// estimate of the Cholesky factor's fill (nested dissection: about n^(4/3) d^2 entries in 3D,
/// n log n in 2D).
double estimate_run_bytes(long long dense_vertices, long long control_vertices,
                          long long control_elements, int d);

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

/// Throws Error (message starts with `where`) when the control mesh exceeds the caps above
/// or the run's estimated memory exceeds 3/4 of usable_memory_bytes(); the message gives the
/// estimate and the cap.
void check_run_size(const std::string& where, long long dense_vertices, long long control_vertices,
                    long long control_elements, int d);

}  // namespace mbi::scenes
