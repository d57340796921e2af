#pragma once
// The memory this process may take, read from the system: the machine's physical memory, the
// limit of its control group (a container), /proc/meminfo's MemAvailable, or a caller's limit.
// The modified-BI precompute's automatic solve path and the callers' refusals
// (scenes::check_run_size, docs/limits.md) read the same limit. Linux files; 0 where unknown
// (other systems, the page's build). Cost: a few small file reads each call.
#include <filesystem>
#include <string>

namespace mbi::interp {

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

/// Bytes this process may still take: /proc/meminfo's MemAvailable, or 0 when it cannot be read.
double available_memory_bytes();

/// The memory a run may take: `max_memory` when > 0 (named "--max-memory"), else the smaller of
/// available_memory_bytes() and usable_memory_bytes(); `name` receives what it is. 0 when unknown.
double memory_limit(double max_memory, std::string& name);

}  // namespace mbi::interp
