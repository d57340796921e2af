#include <mbi/scenes/limits.hpp>
#include <mbi/scenes/scene.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

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
  const double have = usable_memory_bytes();
  if (have <= 0 || need <= have) return "";
  return "needs at least " + gib(need) + " of memory, more than the " + gib(have) + " this process may take";
}

double physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || size <= 0) return 0.0;
  return static_cast<double>(pages) * static_cast<double>(size);
}

namespace {
// The number in a cgroup limit file, 0 for "max", unreadable or unlimited (v1 writes about 2^63).
double limit_in(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string word;
  if (!(in >> word) || word == "max") return 0.0;
  char* end = nullptr;
  const double v = std::strtod(word.c_str(), &end);
  if (end == word.c_str() || *end != '\0' || !(v > 0) || v >= 1152921504606846976.0) return 0.0;  // 2^60
  return v;
}

// The smallest limit in `name` from `dir` up to `top` (both under the mount), 0 when none.
double smallest_up(const std::filesystem::path& top, const std::string& rel, const std::string& name) {
  double best = 0.0;
  std::filesystem::path p = rel;
  for (;;) {
    const double v = limit_in(top / p.relative_path() / name);
    if (v > 0 && (best == 0 || v < best)) best = v;
    if (!p.has_relative_path()) break;
    p = p.parent_path();
  }
  return best;
}
}  // namespace

double cgroup_memory_limit(const std::string& proc_self_cgroup, const std::filesystem::path& root) {
  double best = 0.0;
  auto take = [&](double v) {
    if (v > 0 && (best == 0 || v < best)) best = v;
  };
  std::istringstream lines(proc_self_cgroup);
  std::string line;
  while (std::getline(lines, line)) {
    // hierarchy-ID:controller-list:cgroup-path
    const size_t a = line.find(':'), b = a == std::string::npos ? a : line.find(':', a + 1);
    if (b == std::string::npos) continue;
    const std::string id = line.substr(0, a), controllers = line.substr(a + 1, b - a - 1), path = line.substr(b + 1);
    if (path.empty() || path[0] != '/' || path.find("..") != std::string::npos) continue;
    if (id == "0" && controllers.empty()) {  // v2: the whole mount, or unified/ beside v1
      take(smallest_up(root, path, "memory.max"));
      take(smallest_up(root / "unified", path, "memory.max"));
    } else {
      std::istringstream names(controllers);
      std::string c;
      while (std::getline(names, c, ','))
        if (c == "memory") take(smallest_up(root / "memory", path, "memory.limit_in_bytes"));
    }
  }
  return best;
}

namespace {
// usable_memory_bytes(), and whether the control group's limit is what bounds it
double usable_memory(bool& by_group) {
  const double physical = physical_memory_bytes();
#ifdef __EMSCRIPTEN__  // the page: no file system, no control group; the heap's limit alone
  by_group = false;
  return physical;
#endif
  std::ifstream in("/proc/self/cgroup");
  std::stringstream text;
  text << in.rdbuf();
  const double group = cgroup_memory_limit(text.str(), "/sys/fs/cgroup");
  by_group = group > 0 && (physical <= 0 || group < physical);
  return by_group ? group : physical;
}
}  // namespace

double usable_memory_bytes() {
  bool by_group = false;
  return usable_memory(by_group);
}

double memory_limit(double max_memory, std::string& name) {
  if (max_memory > 0) {
    name = "--max-memory";
    return max_memory;
  }
  bool by_group = false;
  const double usable = usable_memory(by_group), available = interp::available_memory_bytes();
  if (available > 0 && (usable <= 0 || available <= usable)) {
    name = "MemAvailable (/proc/meminfo)";
    return available;
  }
  name = by_group ? "this process's control group limit" : "this machine's memory";
  return usable;
}

interp::MemoryEstimate check_run_size(const std::string& where, long long dense_vertices, const Eigen::MatrixXd& U,
                                      const Eigen::MatrixXi& T, double max_memory, const interp::Options& options,
                                      bool simulation) {
  interp::MemoryEstimate e;
  try {
    e = interp::estimate_memory(U, T, dense_vertices, options);
  } catch (const mbi::Error& err) {  // a size the estimate itself cannot take: named where it came from
    throw Error(where + ": " + err.what());
  }
  if (simulation) {  // the simulator's 12 x 12 (2D: 6 x 6) blocks of each element, as triplets
    const double block = static_cast<double>((U.cols() + 1) * U.cols());
    e.peak_bytes += static_cast<double>(T.rows()) * block * block * 16.0;
  }
  std::string name;
  const double limit = memory_limit(max_memory, name);
  interp::check_memory(e, limit, name, where);
  return e;
}

}  // namespace mbi::scenes
