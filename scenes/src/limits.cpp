#include <mbi/scenes/limits.hpp>
#include <mbi/scenes/scene.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mbi::scenes {

namespace {
std::string gib(double bytes) {
  char b[48];
  std::snprintf(b, sizeof b, "%.3g GiB", bytes / (1024.0 * 1024.0 * 1024.0));
  return b;
}
}  // namespace

double estimate_run_bytes(long long dense_vertices, long long control_vertices,
                          long long control_elements, int d) {
  const double p = static_cast<double>(dense_vertices), n = static_cast<double>(control_vertices);
  const double e = static_cast<double>(control_elements), dd = d;
  // dense: rest + a few per-frame position/normal buffers (double), embedding (element,
  // d + 1 coordinates), float copies for the evaluators
  const double dense = p * (8.0 * dd * 6 + 4.0 + 8.0 * (dd + 1) + 4.0 * dd * 4);
  // control: per-element dense blocks ((d+1) d)^2 as triplets (16 bytes) for assembly, twice
  // (simulator and interpolation); the sparse matrices themselves and the factor's fill
  const double block = ((dd + 1) * dd) * ((dd + 1) * dd);
  const double assembly = 2.0 * e * block * 16.0;
  const double fill = d == 3 ? std::pow(n, 4.0 / 3.0) * dd * dd * 12.0 * 4
                             : n * std::log2(std::max(n, 2.0)) * dd * dd * 12.0 * 4;
  return dense + assembly + fill + n * 1024.0;
}

double physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || size <= 0) return 0.0;
  return static_cast<double>(pages) * static_cast<double>(size);
}

void check_run_size(const std::string& where, long long dense_vertices, long long control_vertices,
                    long long control_elements, int d) {
  const char* kind = d == 3 ? " tetrahedra" : " triangles";
  if (control_vertices > kMaxControlVertices || control_elements > kMaxControlElements)
    throw SceneError(where + ": the control mesh has " + std::to_string(control_vertices) +
                     " vertices and " + std::to_string(control_elements) + kind +
                     ", over the cap of " + std::to_string(kMaxControlVertices) + " vertices and " +
                     std::to_string(kMaxControlElements) + kind +
                     " (the precompute grows about as n^2.5; see docs/limits.md)");
  const double need = estimate_run_bytes(dense_vertices, control_vertices, control_elements, d);
  const double have = physical_memory_bytes();
  if (have > 0 && need > 0.75 * have)
    throw SceneError(where + ": the run needs about " + gib(need) + " of memory (" +
                     std::to_string(dense_vertices) + " dense vertices, " +
                     std::to_string(control_vertices) + " control vertices), over 3/4 of this "
                     "machine's " + gib(have));
}

}  // namespace mbi::scenes
