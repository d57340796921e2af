#include <mbi/scenes/limits.hpp>
#include <mbi/scenes/scene.hpp>

#include <mbi/interp/system_memory.hpp>

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

double minimum_run_bytes(long long dense_vertices, long long control_vertices, long long control_elements, int d) {
  const double p = static_cast<double>(dense_vertices), n = static_cast<double>(control_vertices);
  const double e = static_cast<double>(control_elements), dd = d;
  // dense: positions and the embedding; control: positions, elements, the m-block's entries
  // (value and index) and the simulator's blocks of each element
  return p * (8.0 * dd + 4.0 + 8.0 * (dd + 1)) + n * 8.0 * dd + e * 4.0 * (dd + 1) +
         n * dd * dd * (dd + 2) * 12.0 + e * ((dd + 1) * dd) * ((dd + 1) * dd) * 8.0;
}

std::string over_memory_floor(long long dense_vertices, long long control_vertices, long long control_elements, int d) {
  const double need = minimum_run_bytes(dense_vertices, control_vertices, control_elements, d);
  const double have = interp::usable_memory_bytes();
  if (have <= 0 || need <= have) return "";
  return "needs at least " + gib(need) + " of memory, more than the " + gib(have) + " this process may take";
}

}  // namespace mbi::scenes
